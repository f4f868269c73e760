"""Faults and hostile input, run directories: concurrent writers, signals, read-only and impossible runs roots,
nothing written outside the runs root, sweeps, rl resumed after kill -9: every bad input is one line and a
non-zero exit, and no result is lost silently. docs/reliability.md lists the promises and what tests each; the
other classes of fault are the other tests/test_faults_*.py files (shared helpers: tests/fault_helpers.py)."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import neurosym_cmd, run_dir
from fault_helpers import GOOD, one_line_error, run
from neurosym_cli.utils.io import ArtifactError, write_text
from neurosym_cli.utils.lock import run_lock


# ------------------------------------------------------------------------------------------ concurrency
def test_run_directory_has_one_writer(tmp_path):
    with run_lock(tmp_path / "run"):
        with pytest.raises(ArtifactError, match="is being written by pid"):
            with run_lock(tmp_path / "run"):
                pass
    with run_lock(tmp_path / "run"):  # released: the next writer gets it
        pass


def test_second_train_on_the_same_directory_stops_and_the_first_is_kept(tmp_path):
    """While a process holds a run directory, `neurosym train` there (same or other settings) stops at once."""
    run(["train", "budget=tiny"], tmp_path)
    oracle = tmp_path / "random-cross/tiny/seed0/train/oracle"
    before = (oracle / "model.pt").read_bytes()
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time\nfrom neurosym_cli.utils.lock import run_lock\n"
                               f"with run_lock({str(oracle)!r}):\n    print('held', flush=True)\n    time.sleep(60)"],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        p = run(["train", "budget=tiny", "overwrite=true", "optim.lr=0.5"], tmp_path, check=False)
        one_line_error(p, "is being written by pid")
    finally:
        holder.kill()
        holder.wait()
    assert (oracle / "model.pt").read_bytes() == before


def test_hand_written_program_never_overwrites_the_synthesized_one(tmp_path):
    run(["train", "task=random-grid", "budget=tiny"], tmp_path)
    run(["synth", "task=random-grid", "budget=tiny"], tmp_path)
    run(["eval", "task=random-grid", "baseline=prog", "budget=tiny"], tmp_path)
    exp = tmp_path / "random-grid/tiny/seed0"
    tag = run_dir("synth", tmp_path, "task=random-grid", "budget=tiny").program_tag  # the default search's
    synthesized = (exp / f"eval/prog-{tag}/metrics.json").read_text()
    mine = tmp_path / "mine.txt"
    mine.write_text("random(filter(true, l))\nrandom(filter(true, l))\n")
    run(["eval", "task=random-grid", "baseline=prog", "budget=tiny", f"program={mine}"], tmp_path)
    assert (exp / f"eval/prog-{tag}/metrics.json").read_text() == synthesized
    mine_dirs = [p.name for p in (exp / "eval").glob("prog-file-mine-*")]
    assert len(mine_dirs) == 1 and mine_dirs[0].endswith("-v1")
    # another text under the same name is another result
    mine.write_text("argmax(map(-1.0*d, filter(true, l)))\n")
    run(["eval", "task=random-grid", "baseline=prog", "budget=tiny", f"program={mine}"], tmp_path)
    assert len(list((exp / "eval").glob("prog-file-mine-*"))) == 2
    # a feature this task does not have, a directory, and synth with program= are one line each
    mine.write_text("random(filter(g7x >= 1.0, l))\n")
    one_line_error(run(["eval", "task=random-grid", "baseline=prog", "budget=tiny", f"program={mine}"], tmp_path,
                       check=False), "not in task random-grid")
    one_line_error(run(["retrain", "task=random-grid", "budget=tiny", f"program={mine}"], tmp_path, check=False),
                   "not in task random-grid")
    one_line_error(run(["eval", "task=random-grid", "baseline=prog", "budget=tiny", f"program={tmp_path}"], tmp_path,
                       check=False), "is not a file")
    one_line_error(run(["synth", "task=random-grid", "budget=tiny", f"program={mine}"], tmp_path, check=False),
                   "program= is for eval")
    # a corrupt synthesized program is an error that says how to make it again, never "already synthesized"
    (exp / f"synth/{tag}/program.txt").write_text("random(filter(d >=, l))\n")
    p = run(["synth", "task=random-grid", "budget=tiny"], tmp_path, check=False)
    one_line_error(p, "overwrite=true")
    one_line_error(run(["eval", "task=random-grid", "baseline=prog", "budget=tiny"], tmp_path, check=False),
                   "overwrite=true")
    (exp / f"synth/{tag}/summary.json").write_text('{"rounds": 7, "lam": "x"}')
    (exp / f"synth/{tag}/program.txt").write_text(GOOD.replace("theta", "dy").replace("gd", "gx"))
    p = run(["show-program", "task=random-grid", "budget=tiny"], tmp_path)  # a summary of another shape: no terms
    assert "argmax(map(" in p.stdout
    (exp / "eval/tf-full").mkdir(parents=True, exist_ok=True)
    (exp / "eval/tf-full/metrics.json").write_text('{"label": "tf-full"}')
    one_line_error(run(["report", "task=random-grid", "budget=tiny"], tmp_path, check=False),
                   "not an evaluation written by `neurosym eval`; delete it and run `neurosym pipeline "
                   "task=random-grid budget=tiny seed=0 runs_root=")


# ------------------------------------------------------------------------------------------ signals
def _wait_for(pred, timeout=120.0) -> bool:
    deadline = time.time() + timeout
    while time.time() < deadline:
        if pred():
            return True
        time.sleep(0.01)
    return False


def test_ctrl_c_at_start_up_and_mid_run(tmp_path):
    env = {**os.environ, "NEUROSYM_RUNS": str(tmp_path)}
    # while torch imports (its library is being mapped into the process): one line, exit 130
    p = subprocess.Popen([*neurosym_cmd(), "train", "budget=tiny"], cwd=tmp_path, env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    maps = Path(f"/proc/{p.pid}/maps")
    if _wait_for(lambda: maps.exists() and "libtorch" in maps.read_text()) and p.poll() is None:
        p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=120)
    if p.returncode != 0:  # 0: it finished before the signal arrived (nothing to check)
        assert p.returncode == 130, (p.returncode, err)
        assert "Traceback" not in err and "interrupted" in err.strip().splitlines()[-1], err
    # mid-run: stop after the first checkpoint, then the same command resumes
    args = ["train", "budget=tiny", "budget.train_rollouts=400", "budget.horizon=20", "overwrite=true"]
    p = subprocess.Popen([*neurosym_cmd(), *args], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    history = tmp_path / "random-cross/tiny/seed0/train/oracle/history.csv"
    _wait_for(lambda: history.exists() and len(history.read_text().splitlines()) > 2)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=120)
    if p.returncode == 130:
        assert "re-run the same command to resume" in err and "Traceback" not in err
        again = run(args[:-1], tmp_path)
        assert "resuming" in again.stdout + again.stderr


# ------------------------------------------------------------------------------------------ run directories
def test_runs_root_that_cannot_hold_runs(tmp_path):
    (tmp_path / "file").write_text("")
    one_line_error(run(["train", f"runs_root={tmp_path / 'file' / 'runs'}"], tmp_path, check=False), "is a file")
    one_line_error(run(["report", f"runs_root={tmp_path / 'file'}"], tmp_path, check=False), "is a file")


def test_read_only_runs_directory(tmp_path, monkeypatch):
    """An archived, read-only runs directory: read-only commands log to the temp directory, writing ones stop
    with one line (root writes anywhere, so the check is driven through cli._writable)."""
    from neurosym_cli import cli

    monkeypatch.setattr(cli, "_writable", lambda p: not str(p).startswith(str(tmp_path)))
    args, err = cli._log_dir("show-program", [f"runs_root={tmp_path}"])
    assert err is None and any(a.startswith("hydra.run.dir=") and "neurosym-logs" in a for a in args)
    args, err = cli._log_dir("train", [f"runs_root={tmp_path}"])
    assert err is not None and "read-only" in err


# ------------------------------------------------------------------------------------------ nothing outside the runs root
@pytest.mark.parametrize("arg,needle", [
    ("task.name=../esc", "task.name='../esc' contains '/'"), ("budget.name=../../esc", "budget.name='../../esc'"),
    ("budget.name=..", "budget.name='..' is '..'"), ("task.name=", "task.name='' is empty"),
    ("runs_root=", "runs_root is empty"), ("exp_dir=", "exp_dir is empty"),
    ("exp_dir=../outside", "lies outside runs_root"),
])
def test_names_and_roots_that_would_write_elsewhere_are_one_line(tmp_path, arg, needle):
    root = tmp_path / "root"
    root.mkdir()
    top = set(os.listdir("/"))
    one_line_error(run(["train", "budget=tiny", arg], root, check=False), needle)
    assert os.listdir(tmp_path) == ["root"] and set(os.listdir("/")) <= top  # nothing beside or above the root
    assert not list(root.rglob("model.pt"))


def test_every_write_is_checked_against_the_runs_root(tmp_path):
    from neurosym_cli.utils.io import confine

    confine([tmp_path / "root"])
    try:
        write_text(tmp_path / "root" / "a" / "ok.txt", "x")
        for where in (tmp_path / "elsewhere.txt", tmp_path / "root" / ".." / "esc.txt"):
            with pytest.raises(ArtifactError, match="outside the runs root"):
                write_text(where, "x")
        with pytest.raises(ArtifactError, match="outside the runs root"):
            with run_lock(tmp_path / "run"):
                pass
    finally:
        confine([])
    assert sorted(os.listdir(tmp_path)) == ["root"]


# ------------------------------------------------------------------------------------------ sweeps
def _job_dir(sweep: Path, name: str, result=None, raw: bytes | None = None, age: float = 0.0) -> Path:
    d = sweep / name
    (d / ".hydra").mkdir(parents=True)
    (d / ".hydra" / "overrides.yaml").write_text("[]\n")
    if result is not None:
        (d / "job_result.json").write_text(__import__("json").dumps(result))
    if raw is not None:
        (d / "job_result.json").write_bytes(raw)
    if age:  # Hydra started it this long before the current sweep
        t = time.time() - age
        os.utime(d / ".hydra" / "overrides.yaml", (t, t))
    return d


def test_a_malformed_job_result_is_a_failed_job_and_fails_the_sweep(tmp_path, capsys):
    from omegaconf import OmegaConf

    from neurosym_cli.commands.sweep import SweepSummary, collect, start

    sweep = tmp_path / "sweep"
    sweep.mkdir()
    _job_dir(sweep, "9_seed=9", {"ok": True, "job": 9, "overrides": ["seed=9"], "row": {}}, age=3600)  # earlier
    sid = start(sweep)
    _job_dir(sweep, "0_seed=0", {"ok": True, "job": 0, "overrides": ["seed=0"], "sweep": sid, "row": {"loss": 1.5}})
    _job_dir(sweep, "1_seed=1", [1, 2])
    _job_dir(sweep, "2_seed=2", {"ok": "yes", "job": 2, "overrides": "seed=2", "sweep": sid})
    _job_dir(sweep, "3_seed=3", {"ok": True, "job": 3, "overrides": ["seed=3"], "sweep": sid, "row": 7})
    _job_dir(sweep, "4_seed=4", raw=b"\xff{")
    _job_dir(sweep, "5_seed=5")  # started, then killed before it wrote anything
    rows = collect(sweep)
    assert [(r["job"], r["ok"]) for r in rows] == [(0, True), (1, False), (2, False), (3, False), (4, False),
                                                   (5, False)]
    assert "malformed" in rows[1]["error"] and "no result" in rows[5]["error"]
    with pytest.raises(SystemExit) as e:
        SweepSummary().on_multirun_end(OmegaConf.create({"cmd": "train", "hydra": {"sweep": {"dir": str(sweep)}}}))
    assert e.value.code == 1
    out = capsys.readouterr().out
    assert "6 jobs" in out and "5 of 6 jobs failed" in out and "seed=9" not in out


def test_a_reused_sweep_directory_lists_only_this_sweeps_jobs(tmp_path):
    sweep = tmp_path / "sweep"
    _job_dir(sweep, "7_seed=7", {"ok": True, "job": 7, "overrides": ["seed=7"], "row": {}}, age=60)  # a sweep before
    prog = tmp_path / "p.txt"
    prog.write_text("random(filter(true, l))\n")
    p = run(["show-program", "-m", "seed=0,1", "task=random-grid", "budget=tiny", f"program={prog}",
             f"hydra.sweep.dir={sweep}"], tmp_path)
    assert ": 2 jobs" in p.stdout and "seed=0" in p.stdout and "seed=1" in p.stdout and "seed=7" not in p.stdout


# ------------------------------------------------------------------------------------------ rl reproducible
def _rl_run(runs: Path) -> tuple[list[list[str]], dict]:
    """An rl model's history (without the wall-clock column) and its weights (transformer and gate)."""
    import torch

    out = runs / "random-grid/tiny/seed0/train/rl-c0.1-togo-scratch"
    rows = [line.split(",") for line in (out / "history.csv").read_text().splitlines()]
    col = rows[0].index("seconds")
    ckpt = torch.load(out / "model.pt", weights_only=True)
    return [r[:col] + r[col + 1:] for r in rows], {**ckpt["state_dict"], **{f"gate.{k}": v for k, v in
                                                                           ckpt["comm_state"].items()}}


def test_rl_is_reproducible_and_a_kill_9_resumes_exactly(tmp_path):
    """Issue 28, item 6: the same seed and threads give the same rl weights and history, and a run killed with
    SIGKILL after a checkpoint and run again ends where the uninterrupted run ends (its gate's initial weights are
    drawn from the seed; its running mean return travels in the checkpoint)."""
    import torch

    args = ["train", "task=random-grid", "budget=tiny", "threads=1", "baseline=rl", "rl.init=scratch",
            "budget.train_rollouts=48"]
    roots = [tmp_path / r for r in ("a", "b", "killed")]
    for r in roots[:2]:
        r.mkdir()
        run(args, r)
    (a_hist, a_w), (b_hist, b_w) = _rl_run(roots[0]), _rl_run(roots[1])
    assert a_hist == b_hist and len(a_hist) == 13
    assert all(torch.equal(a_w[k], b_w[k]) for k in a_w)
    killed = roots[2]
    killed.mkdir()
    env = {**os.environ, "NEUROSYM_RUNS": str(killed)}
    p = subprocess.Popen([*neurosym_cmd(), *args], cwd=killed, env=env, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    history = killed / "random-grid/tiny/seed0/train/rl-c0.1-togo-scratch/history.csv"
    _wait_for(lambda: history.exists() and len(history.read_text().splitlines()) > 3, timeout=120)
    p.kill()
    p.wait()
    again = run(args, killed)
    assert "resuming" in again.stdout + again.stderr  # it was killed mid-run, not after the end
    k_hist, k_w = _rl_run(killed)
    assert k_hist == a_hist
    assert all(torch.equal(a_w[k], k_w[k]) for k in a_w)
