"""The pipeline's scheduler (stages/flow.py): waits, batches, errors, worker processes set up as the command; and the
pipeline run with stages at once gives the numbers of the pipeline run one stage after the other (issue 39)."""

import os
import time
from pathlib import Path

import pytest

from neurosym_cli.config import UserError
from neurosym_cli.stages.flow import Job, Node, one, run_flow


def stamp(name: str, log: str, seconds: float = 0.0) -> tuple[str, int, float, float]:
    """A job: sleeps, appends its name to ``log``, returns (name, pid, start, end)."""
    start = time.time()
    time.sleep(seconds)
    with open(log, "a") as f:
        f.write(name + "\n")
    return name, os.getpid(), start, time.time()


def fail(message: str) -> None:
    raise UserError(message)


def job_node(key: str, log: str, needs=(), seconds=0.0) -> Node:
    return Node(key, lambda: one(Job(stamp, (key, log, seconds), key)), tuple(needs))


def settings() -> dict:
    """A job that reports how its process is set up, and logs a line."""
    import torch

    from neurosym_cli.utils.compiling import in_effect
    from neurosym_cli.utils.console import log
    from neurosym_cli.utils.io import confined

    log.info("a line from the job")
    return {"threads": torch.get_num_threads(), "compile": in_effect(), "roots": [str(r) for r in confined()]}


def pid_then_sleep(path: str) -> None:
    with open(path, "w") as f:
        f.write(str(os.getpid()))
    time.sleep(60)


def die() -> None:
    os._exit(3)


def test_in_this_process_the_nodes_run_in_order_as_their_waits_allow(tmp_path):
    log = str(tmp_path / "log")
    nodes = [job_node("c", log, needs=["a"]), job_node("a", log), job_node("b", log)]
    seen = []
    values = run_flow(nodes, 1, on_result=seen.append)
    assert open(log).read().split() == ["a", "c", "b"]  # c waited for a, then came first in the list
    assert {k: v[0] for k, v in values.items()} == {"a": "a", "b": "b", "c": "c"}
    assert all(v[1] == os.getpid() for v in values.values()) and len(seen) == 3


def test_a_node_of_batches_is_sent_each_batch_and_returns_its_value(tmp_path):
    log = str(tmp_path / "log")

    def batches():
        first = yield [Job(stamp, ("x", log), "x"), Job(stamp, ("y", log), "y")]
        second = yield [Job(stamp, (f"after-{len(first)}", log), "z")]
        return [r[0] for r in first + second]

    values = run_flow([Node("b", batches)], 1)
    assert values["b"] == ["x", "y", "after-2"]


def test_workers_run_two_at_once_and_keep_waits(tmp_path):
    log = str(tmp_path / "log")
    nodes = [job_node("a", log, seconds=1.0), job_node("b", log, seconds=1.0),
             job_node("c", log, needs=["a"], seconds=0.5), job_node("d", log, needs=["c", "b"])]
    values = run_flow(nodes, 2)
    pids = {v[1] for v in values.values()}
    assert os.getpid() not in pids and len(pids) == 2  # spawned workers, both used
    a, b, c, d = (values[k] for k in "abcd")
    assert a[2] < b[3] and b[2] < a[3]  # a and b overlapped
    assert c[2] >= a[3] and d[2] >= max(b[3], c[3])  # each waited for what it needs


def test_a_worker_is_set_up_as_the_command_is(tmp_path):
    """threads, compile mode, where it may write, the command's log file and its multirun prefix before the job's."""
    from neurosym_cli.stages.flow import Worker

    log_file = tmp_path / "pipeline.log"
    worker = Worker(threads=2, compile="off", roots=(str(tmp_path),), log_file=str(log_file),
                    log_format="[%(levelname)s] %(message)s", prefix="seed=1")
    values = run_flow([Node(k, lambda: one(Job(settings, (), "stage x"))) for k in ("p", "q")], 2, worker=worker)
    assert values["p"] == {"threads": 2, "compile": "off", "roots": [str(tmp_path.resolve())]}
    assert "[INFO] [seed=1 stage x] a line from the job" in log_file.read_text()


def test_a_worker_ends_with_the_process_that_started_it(tmp_path):
    """kill -9 of the command: its workers do not go on unseen holding their run directories' locks."""
    import signal
    import subprocess
    import sys

    pid_file = tmp_path / "worker.pid"
    code = (f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
            "from neurosym_cli.stages.flow import Job, Node, one, run_flow\n"
            "from test_flow import pid_then_sleep\n"
            "if __name__ == '__main__':\n"
            f"    run_flow([Node(k, lambda: one(Job(pid_then_sleep, ({str(pid_file)!r},), k))) for k in 'ab'], 2)\n")
    parent = subprocess.Popen([sys.executable, "-c", code])
    try:
        deadline = time.time() + 60
        while not (pid_file.exists() and pid_file.read_text()) and time.time() < deadline:
            time.sleep(0.2)
        worker = int(pid_file.read_text())
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait()
        deadline = time.time() + 10
        while time.time() < deadline and Path(f"/proc/{worker}").exists() and \
                "zombie" not in Path(f"/proc/{worker}/status").read_text().lower():
            time.sleep(0.2)
        assert not Path(f"/proc/{worker}").exists() or "zombie" in Path(f"/proc/{worker}/status").read_text().lower()
    finally:
        parent.kill()


def test_a_dead_worker_is_one_line_that_says_how_to_resume():
    with pytest.raises(UserError, match="a worker process died.*rerun the same command to resume"):
        run_flow([Node("x", lambda: one(Job(die, (), "x")))], 2)


def test_a_stage_waits_for_what_an_absent_stage_waited_for():
    """program=: prog's search is not run, so prog-retrained's retraining waits for the oracle directly."""
    from neurosym_cli.stages.graph import Stage
    from neurosym_cli.stages.pipeline import waits

    stages = [Stage("train", "tf-full"), Stage("retrain", "prog-retrained"), Stage("eval", "prog-retrained")]
    assert waits(Stage("retrain", "prog-retrained"), stages) == [Stage("train", "tf-full")]
    assert waits(Stage("eval", "prog-retrained"), stages) == [Stage("train", "tf-full"),
                                                              Stage("retrain", "prog-retrained")]


def test_an_error_in_a_worker_stops_the_flow_with_its_message(tmp_path):
    log = str(tmp_path / "log")
    nodes = [Node("bad", lambda: one(Job(fail, ("the model diverged; rerun with overwrite=true",), "bad"))),
             job_node("slow", log, seconds=30.0), job_node("later", log, needs=["bad"])]
    t0 = time.time()
    with pytest.raises(UserError, match="the model diverged"):
        run_flow(nodes, 2)
    assert time.time() - t0 < 25  # the running job was stopped, not waited for
    assert not os.path.exists(log) or "later" not in open(log).read()


def test_a_cycle_or_an_unknown_wait_is_refused(tmp_path):
    log = str(tmp_path / "log")
    with pytest.raises(ValueError, match="cycle"):
        run_flow([job_node("a", log, needs=["b"]), job_node("b", log, needs=["a"])], 1)
    with pytest.raises(ValueError, match="unknown"):
        run_flow([job_node("a", log, needs=["nowhere"])], 1)


def test_the_pipeline_with_stages_at_once_makes_the_same_numbers(tmp_path):
    """pipeline.jobs=2 (the front selection's validations and retrainings in workers too) against pipeline.jobs=1:
    every checkpoint, dataset, program and evaluation row equal (benchmarks/fingerprint.py)."""
    import json

    from benchmarks.fingerprint import fingerprint
    from test_cli import run

    for d in ("one", "two"):
        (tmp_path / d).mkdir()
    base = ["pipeline", "task=random-grid", "budget=tiny", "baselines=[tf-full,prog-retrained,no-comm]"]
    one_at_a_time = run([*base, "pipeline.jobs=1"], tmp_path / "one")
    at_once = run([*base, "pipeline.jobs=2"], tmp_path / "two")
    assert "up to 2 at once" in at_once.stdout and "at once" not in one_at_a_time.stdout
    assert "[retrain k2-lam0.5-v1-hybrid-b" in at_once.stdout  # a candidate's lines name it
    a, b = fingerprint(tmp_path / "one"), fingerprint(tmp_path / "two")
    assert a == b and len(a) >= 10
    lines = [ln for ln in at_once.stdout.splitlines() if "pipeline stage " in ln]
    assert len(lines) == 7 and lines[0].split("pipeline stage ")[1].startswith("1/7: train tf-full")
    timings = json.loads((tmp_path / "two/random-grid/tiny/seed0/pipeline_timings.json").read_text())
    assert {"train tf-full", "train no-comm", "synth prog", "eval prog-retrained"} <= {k.rsplit(" k2", 1)[0]
                                                                                        for k in timings}


def test_pipeline_jobs_is_one_per_usable_core_over_threads():
    import dataclasses

    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.stages.pipeline import pipeline_jobs

    cfg = compose_config("pipeline", ["task=random-grid", "pipeline.jobs=0", "device=cpu"])
    cores = len(os.sched_getaffinity(0))
    assert pipeline_jobs(cfg) == cores  # threads=1, the default
    assert pipeline_jobs(dataclasses.replace(cfg, threads=0)) == 1  # one stage already takes every core
    assert pipeline_jobs(dataclasses.replace(cfg, pipeline=dataclasses.replace(cfg.pipeline, jobs=3))) == 3
    assert compose_config("pipeline", ["task=random-grid"]).pipeline.jobs == int(os.environ["NEUROSYM_PIPELINE_JOBS"])


def test_from_a_python_script_the_stages_run_in_its_process_unless_asked(tmp_path):
    """api.pipeline: pipeline.jobs=0 means 1 from Python (workers import the calling script again); asked for two
    workers, a script without a main guard gets one line that says so."""
    import subprocess
    import sys

    script = tmp_path / "mine.py"
    script.write_text("from neurosym_cli import api\n"
                      "cfg = api.compose('pipeline', ['task=random-grid', 'budget=tiny', "
                      "'baselines=[tf-full]', 'plots=false', *__import__('sys').argv[1:]])\n"
                      "print(sorted(api.pipeline(cfg)))\n")
    env = {k: v for k, v in os.environ.items() if k != "NEUROSYM_PIPELINE_JOBS"}
    p = subprocess.run([sys.executable, str(script), f"runs_root={tmp_path / 'a'}"], capture_output=True, text=True,
                       env=env, timeout=300)
    assert p.returncode == 0 and "['eval:tf-full', 'train:tf-full']" in p.stdout, p.stderr
    p = subprocess.run([sys.executable, str(script), f"runs_root={tmp_path / 'b'}", "pipeline.jobs=2"],
                       capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode != 0 and 'if __name__ == "__main__":' in p.stderr and "pipeline.jobs=1" in p.stderr
