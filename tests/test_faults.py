"""Faults and hostile input: every bad input is one line and a non-zero exit, and no result is lost silently.

Probes by class (docs/reliability.md lists the promises and what tests each): program text (size, depth,
encoding, numbers, a directory, mutations), every artifact truncated, emptied, of the wrong type or a directory,
concurrent writers, signals, read-only and impossible run directories, overrides (typos, types, quoting, ranges),
and file modes. Fast cases run in CI; benchmarks/fuzz_parser.py is the longer fuzz run.
"""

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

import pytest

from conftest import neurosym_cmd
from neurosym_cli.config import ConfigError
from neurosym_cli.dsl import ProgramSyntaxError, parse, to_text
from neurosym_cli.dsl.files import load_program
from neurosym_cli.utils.io import ArtifactError, read_json, write_text
from neurosym_cli.utils.lock import run_lock


def run(args, runs, check=True, timeout=300, **kw):
    env = {**os.environ, "NEUROSYM_RUNS": str(runs)}
    p = subprocess.run([*neurosym_cmd(), *args], cwd=runs, env=env, capture_output=True, text=True, timeout=timeout,
                       **kw)
    if check and p.returncode != 0:
        raise AssertionError(f"exit {p.returncode}\nstdout:\n{p.stdout}\nstderr:\n{p.stderr}")
    return p


def one_line_error(p, needle: str) -> None:
    """A non-zero exit, no traceback, and the reason in the last line of stderr."""
    assert p.returncode != 0, p.stdout
    assert "Traceback" not in p.stderr and "Error executing job" not in p.stderr, p.stderr
    assert needle in p.stderr.strip().splitlines()[-1], p.stderr


# ------------------------------------------------------------------------------------------ program text
GOOD = "argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nrandom(filter(d >= 3.41 and gd <= 2.0, l))\n"


@pytest.mark.parametrize("text,needle", [
    ("random(filter(d >= 1e400, l))", "out of range"),
    ("random(filter(d >= -1e999, l))", "out of range"),
    ("argmax(map(1e400*d, filter(true, l)))", "out of range"),
    ("random(filter(d >= \u0661\u0662, l))", "unexpected character"),  # Arabic-Indic digits are not numbers
    ("random(filter(" + "(" * 200 + "d >= 1" + ")" * 200 + ", l))", "nested deeper"),
    ("random(filter(" + " and ".join(["d >= 1"] * 500) + ", l))", "nested deeper"),
    ("random(filter(" + " or ".join(["d >= 1"] * 500) + ", l))", "nested deeper"),
    ("random(filter(d >= 1, l))" + "x" * 20_000, "characters long"),
    ("random(filter(" + "d" * 5_000 + " >= 1, l))", "unknown"),
])
def test_hostile_program_text_is_a_syntax_error(text, needle):
    try:
        parse(text)
    except ProgramSyntaxError as e:
        assert e.line >= 1 and e.col >= 1
        assert len(str(e)) < 300  # a huge token is quoted in part, never whole
        if needle != "unknown":
            assert needle in str(e)
    else:  # a 5,000-letter feature name parses; the task check refuses it (test below)
        assert needle == "unknown"


def test_parser_is_linear_in_the_line_length():
    """An 11 MB line is refused at once (before tokenizing); a rule of 1,200 terms parses."""
    t0 = time.perf_counter()
    with pytest.raises(ProgramSyntaxError, match="characters long"):
        parse("random(filter(" + "d >= 1 and " * 1_000_000)
    assert time.perf_counter() - t0 < 5
    long_rule = "argmax(map(" + " + ".join(f"w{k}" for k in range(1200)) + ", filter(true, l)))"
    assert len(long_rule) < 10_000 and len(parse(long_rule).rounds[0][0].score.terms) == 1200


def test_program_files_that_are_not_text(tmp_path):
    (tmp_path / "latin1.txt").write_bytes("random(filter(d >= 1, l))  # caf\xe9\n".encode("latin-1"))
    with pytest.raises(ArtifactError, match="not UTF-8 text"):
        load_program(tmp_path / "latin1.txt")
    with pytest.raises(ArtifactError, match="is not a file"):
        load_program(tmp_path)
    with pytest.raises(ArtifactError, match="no program at"):
        load_program(tmp_path / "missing.txt")
    (tmp_path / "empty.txt").write_text("")
    with pytest.raises(ArtifactError, match="at least one rule"):
        load_program(tmp_path / "empty.txt", "neurosym synth ...")


def _mutate(text: str, rng: random.Random) -> str:
    alphabet = "()=<>,.-+*#:0123456789 \n\tabcdefghijklmnopqrstuvwxyz_\u00e9\u0661\x00"
    chars = list(text)
    for _ in range(rng.randint(1, 6)):
        op = rng.random()
        k = rng.randrange(len(chars) + 1)
        if op < 0.4 and chars:
            del chars[min(k, len(chars) - 1)]
        elif op < 0.8:
            chars.insert(k, rng.choice(alphabet))
        else:
            chars[k:k] = chars[rng.randrange(len(chars)):][: rng.randint(1, 30)]  # duplicate a slice
    return "".join(chars)


def fuzz_parser(cases: int, seed: int) -> tuple[int, int]:
    """Mutations of a valid program: each parses to a program that prints and parses back the same, or raises
    ProgramSyntaxError; anything else fails. Returns (parsed, rejected)."""
    rng = random.Random(seed)
    parsed = rejected = 0
    for _ in range(cases):
        text = _mutate(GOOD, rng)
        try:
            p = parse(text)
        except ProgramSyntaxError:
            rejected += 1
            continue
        assert parse(to_text(p)) == p, text
        parsed += 1
    return parsed, rejected


def test_parser_mutations_parse_back_or_are_syntax_errors():
    parsed, rejected = fuzz_parser(3_000, seed=0)
    assert parsed > 30 and rejected > 1_000  # both outcomes are exercised


@pytest.mark.slow
def test_parser_fuzz_long():
    parsed, rejected = fuzz_parser(60_000, seed=1)
    assert parsed + rejected == 60_000


# ------------------------------------------------------------------------------------------ artifacts
@pytest.mark.parametrize("content", [b"", b"{", b"[1, 2]", b'{"label": 3}', b"\xff\xfe", None])
def test_malformed_metrics_are_one_line(tmp_path, content):
    from neurosym_cli.seeds import from_run_dir
    from neurosym_cli.stages.results import collect

    f = tmp_path / "eval" / "tf-full" / "metrics.json"
    if content is None:
        f.mkdir(parents=True)  # a directory where the file should be
    else:
        f.parent.mkdir(parents=True)
        f.write_bytes(content)
    with pytest.raises(ArtifactError):
        collect(tmp_path)
    with pytest.raises(ArtifactError):
        from_run_dir(tmp_path)  # the same file read across training seeds (`neurosym report`)


def test_read_json_maps_every_failure_to_one_error(tmp_path):
    for content in (b"", b"\xff", b"{]"):
        (tmp_path / "x.json").write_bytes(content)
        with pytest.raises(ArtifactError, match="cannot read"):
            read_json(tmp_path / "x.json")
    with pytest.raises(ArtifactError):
        read_json(tmp_path)


@pytest.mark.parametrize("content", [b"", b"not a checkpoint", b"PK\x03\x04" + b"\x00" * 100, None])
def test_corrupt_torch_files_are_artifact_errors(tmp_path, content):
    from neurosym_cli.artifacts import load_checkpoint

    f = tmp_path / "model.pt"
    if content is None:
        f.mkdir()
    else:
        f.write_bytes(content)
    with pytest.raises(ArtifactError, match="model.pt"):
        load_checkpoint(f, "neurosym train ...")


def test_a_pickle_with_code_is_refused(tmp_path):
    """Checkpoints load with weights_only=True: a pickle that would run code on load is a corrupt file."""
    import pickle

    from neurosym_cli.artifacts import load_checkpoint

    class Boom:
        def __reduce__(self):
            return (os.system, ("echo pwned > " + str(tmp_path / "pwned"),))

    f = tmp_path / "model.pt"
    f.write_bytes(pickle.dumps({"format": "neurosym-policy/1", "x": Boom()}))
    with pytest.raises(ArtifactError, match="corrupt"):
        load_checkpoint(f, "neurosym train ...")
    assert not (tmp_path / "pwned").exists()


def test_writes_follow_the_umask(tmp_path):
    write_text(tmp_path / "a.txt", "x")
    mask = os.umask(0)
    os.umask(mask)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o666 & ~mask


def test_writing_under_a_file_is_an_artifact_error(tmp_path):
    (tmp_path / "f").write_text("")
    with pytest.raises(ArtifactError, match="cannot write"):
        write_text(tmp_path / "f" / "x.json", "{}")


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
    synthesized = (exp / "eval/prog-k2-lam0.5-v1/metrics.json").read_text()
    mine = tmp_path / "mine.txt"
    mine.write_text("random(filter(true, l))\nrandom(filter(true, l))\n")
    run(["eval", "task=random-grid", "baseline=prog", "budget=tiny", f"program={mine}"], tmp_path)
    assert (exp / "eval/prog-k2-lam0.5-v1/metrics.json").read_text() == synthesized
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
    (exp / "synth/k2-lam0.5-v1/program.txt").write_text("random(filter(d >=, l))\n")
    p = run(["synth", "task=random-grid", "budget=tiny"], tmp_path, check=False)
    one_line_error(p, "overwrite=true")
    one_line_error(run(["eval", "task=random-grid", "baseline=prog", "budget=tiny"], tmp_path, check=False),
                   "overwrite=true")
    (exp / "synth/k2-lam0.5-v1/summary.json").write_text('{"rounds": 7, "lam": "x"}')
    (exp / "synth/k2-lam0.5-v1/program.txt").write_text(GOOD.replace("theta", "dy").replace("gd", "gx"))
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


# ------------------------------------------------------------------------------------------ overrides
@pytest.mark.parametrize("arg,needle", [
    ("seeed=1", "did you mean 'seed'"), ("lamda=0.3", "did you mean 'lam'"), ("+foo=1", "unknown key 'foo'"),
    ("task.colision_weight=3", "did you mean 'task.collision_weight'"), ("seed=abc", "takes an integer"),
    ("lam=0.3,abc", "takes a number"), ("overwrite=maybe", "takes true or false"),
    ("runs_root=\u00e9t\u00e9", "only in quotes"),
])
def test_bad_overrides_are_named(arg, needle):
    from neurosym_cli.overrides import check
    from neurosym_cli.tasks.random_cross import CrossConfig  # the task's own keys come from its schema

    assert needle in (check(["-m", arg], [CrossConfig]) or "")


@pytest.mark.parametrize("arg,needle", [("seeed=1", "did you mean 'seed'"), ("seed=abc", "takes an integer"),
                                        ("rules=1000", "at most 40 - 1"), ("threads=999", "CPU")])
def test_bad_overrides_are_one_line(tmp_path, arg, needle):
    one_line_error(run(["train", arg], tmp_path, check=False), needle)


def test_good_overrides_pass_the_check():
    from neurosym_cli.overrides import check
    from neurosym_cli.tasks.random_cross import CrossConfig  # task.num_groups is a key of the cross tasks' schema

    assert check(["seed=0,1,2", "lam=0.3,0.5", "budget.horizon=null", "task.num_groups=2", "hydra/launcher=joblib",
                  "hydra.launcher.n_jobs=2", "baselines=[tf-full,prog]", "seed=range(0,3)", "-m", "--cfg", "job",
                  "runs_root='\u00e9t\u00e9'", "synth.backend=torch", "+seed=3"], [CrossConfig]) is None


def test_rules_and_threads_ranges_in_the_schema():
    from neurosym_cli.commands.apps import compose_config

    with pytest.raises(ConfigError, match="rules=30"):
        compose_config("train", ["task=random-grid", "rules=30"])
    assert compose_config("train", ["task=random-grid", "rules=29"]).rules == 29


def test_unwritable_system_path_is_one_line(tmp_path):
    one_line_error(run(["train", "runs_root=/proc/neurosym"], tmp_path, check=False), "cannot write")


def test_other_corrupt_artifacts(tmp_path):
    """A corrupt tree is one line naming overwrite=true; a corrupt dataset is collected again; a corrupt
    training history counts as no time."""
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.stages.comm import baseline_comm
    from neurosym_cli.stages.pipeline import _trained_seconds

    cfg = compose_config("eval", ["baseline=dt", "budget=tiny", f"runs_root={tmp_path}"])
    tree = tmp_path / "random-cross/tiny/seed0/synth/dt-k5-v1/tree.json"
    tree.parent.mkdir(parents=True)
    for content in ('{"rounds": [{"left": 1}]}', '{"rounds": 3}', "[]"):
        tree.write_text(content)
        with pytest.raises(ArtifactError, match="overwrite=true"):
            baseline_comm(cfg)
    (tmp_path / "history.csv").write_text("step,loss\n1,2\n")  # no seconds column
    assert _trained_seconds(tmp_path / "history.csv") == 0.0


def test_corrupt_dataset_is_collected_again(tmp_path):
    import torch

    from neurosym_cli.config import ModelConfig
    from neurosym_cli.tasks.random_cross import CrossConfig
    from neurosym_cli.tasks import make_task
    from neurosym_cli.policy import CommTransformer
    from neurosym_cli.synth.dataset import load_or_collect

    env = make_task(CrossConfig(name="c", horizon=4))
    pol = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig())
    path = tmp_path / "dataset.pt"
    path.write_bytes(b"\x80\x04garbage")
    data = load_or_collect(path, "neurosym synth", env, pol, 2, 2, torch.Generator().manual_seed(0),
                           torch.device("cpu"))
    assert data and sum(b.states for b in data) == 2 * 2  # 2 rollouts, every 2nd of 4 steps
    again = load_or_collect(path, "neurosym synth", env, pol, 2, 2, torch.Generator().manual_seed(5),
                            torch.device("cpu"))
    assert torch.equal(again[0].target, data[0].target)  # reused, not collected with the other generator


# ------------------------------------------------------------------------------------------ no NaN is a result
@pytest.mark.parametrize("args,needle", [
    (["optim.lr=1e6"], "training diverged at step"),
    (["task.dt=1e30"], "task.dt must lie in"),
    (["task.v_max=1e308"], "task.v_max must lie in"),
    (["lam=inf"], "lam must be a finite number"),
    (["synth.temperature=nan"], "synth.temperature must be a finite number"),
    (["optim.retrain_lr=inf"], "optim.retrain_lr must be a finite number"),
])
def test_a_diverging_or_non_finite_run_is_one_line_and_never_trained(tmp_path, args, needle):
    import torch

    p = run(["train", "budget=tiny", *args], tmp_path, check=False)
    one_line_error(p, needle)
    for ckpt in tmp_path.rglob("model.pt"):  # what a diverged run keeps is finite and not marked trained
        payload = torch.load(ckpt, weights_only=True)
        assert not payload["done"] and all(torch.isfinite(t).all() for t in payload["state_dict"].values())


def test_a_checkpoint_with_non_finite_weights_is_refused(tmp_path):
    """A NaN checkpoint (as a diverged training saved before this check) is refused by eval, synth and resume."""
    import torch

    run(["train", "budget=tiny"], tmp_path)
    ckpt = tmp_path / "random-cross/tiny/seed0/train/oracle/model.pt"
    payload = torch.load(ckpt, weights_only=True)
    next(iter(payload["state_dict"].values())).fill_(float("nan"))
    torch.save(payload, ckpt)
    for verb in (["eval", "baseline=tf-full"], ["synth"], ["train", "budget.train_rollouts=16"]):
        one_line_error(run([*verb, "budget=tiny"], tmp_path, check=False), "non-finite weights")
    assert not (tmp_path / "random-cross/tiny/seed0/eval/tf-full/metrics.json").exists()


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


# ------------------------------------------------------------------------------------------ keyed results
def test_an_evaluation_is_of_the_condition_and_baseline_it_names(tmp_path):
    """eval refuses an option its baseline ignores (program= for tf-full) and a task condition other than the
    model's training (it would replace the trained condition's metrics); protocol keys may differ."""
    common = ["task=random-grid", "budget=tiny", "plots=false"]
    run(["train", *common], tmp_path)
    run(["eval", *common, "baseline=tf-full"], tmp_path)
    metrics = tmp_path / "random-grid/tiny/seed0/eval/tf-full/metrics.json"
    before = metrics.read_bytes()
    mine = tmp_path / "mine.txt"
    mine.write_text("random(filter(true, l))\nrandom(filter(true, l))\n")
    one_line_error(run(["eval", *common, "baseline=tf-full", f"program={mine}"], tmp_path, check=False),
                   "program= is for the baselines that run under a program")
    p = run(["eval", *common, "baseline=tf-full", "task.noise_std=0.5"], tmp_path, check=False)
    one_line_error(p, "was trained with task.noise_std=0.05, this run has 0.5")
    assert metrics.read_bytes() == before
    # resuming under another condition names the key too (the same comparison)
    one_line_error(run(["train", *common, "task.noise_std=0.5", "budget.train_rollouts=16"], tmp_path, check=False),
                   "was trained with task.noise_std=0.05")
    run(["eval", *common, "baseline=tf-full", "task.eval_episodes=2"], tmp_path)  # the protocol, not the condition


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


# ------------------------------------------------------------------------------------------ issue 28, item 4
@pytest.fixture(scope="module")
def trained_root(tmp_path_factory):
    """A runs root with random-grid's tiny oracle and its synthesized program (made once for this module)."""
    root = tmp_path_factory.mktemp("trained")
    run(["train", "task=random-grid", "budget=tiny", "threads=1"], root)
    run(["synth", "task=random-grid", "budget=tiny", "threads=1"], root)
    return root


@pytest.fixture
def runs(trained_root, tmp_path):
    """A private copy of ``trained_root`` (a test may break its artifacts)."""
    import shutil

    shutil.copytree(trained_root, tmp_path / "runs", symlinks=True)
    return tmp_path / "runs"


EXP = "random-grid/tiny/seed0"
TINY = ["task=random-grid", "budget=tiny", "threads=1"]


def test_a_hand_written_programs_metrics_record_its_own_k(runs):
    """Issue 28, item 2: K of a program given as program=FILE is the file's (3 rules), not the config's rules=2."""
    import json

    prog = runs / "three.txt"
    prog.write_text("random(filter(d <= 2.0, l))\nrandom(filter(d <= 3.0, l))\nrandom(filter(gy >= -1.0, l))\n")
    run(["eval", "baseline=prog", *TINY, f"program={prog}"], runs)
    (out,) = (runs / EXP / "eval").glob("prog-file-three-*/metrics.json")
    assert json.loads(out.read_text())["rules"] == 3
    run(["eval", "baseline=prog", *TINY], runs)  # the synthesized program's is its search's K
    assert json.loads((runs / EXP / "eval/prog-k2-lam0.5-v1/metrics.json").read_text())["rules"] == 2


def test_no_nan_from_a_finite_model_or_a_nan_dataset(runs):
    """Issue 28, item 1: a dataset D holding a nan is never searched on (collected again), an oracle whose
    rollouts overflow (weights finite, 1e30 times too large) is refused by synth and eval in one line, and no
    metrics.json or program is written from it."""
    import torch

    data = runs / EXP / "synth/dataset-r4-s10.pt"
    payload = torch.load(data, weights_only=True)
    payload["buckets"][0]["rel"].view(-1)[0] = float("nan")
    torch.save(payload, data)
    p = run(["synth", *TINY, "overwrite=true"], runs)
    assert "holds non-finite values (buckets[0].rel); collecting it again" in p.stdout + p.stderr
    assert all(torch.isfinite(b["rel"]).all() for b in torch.load(data, weights_only=True)["buckets"])
    ckpt = runs / EXP / "train/oracle/model.pt"
    payload = torch.load(ckpt, weights_only=True)
    for w in payload["state_dict"].values():
        w.mul_(1e30)
    torch.save(payload, ckpt)
    data.unlink()
    one_line_error(run(["synth", *TINY, "overwrite=true"], runs, check=False), "rollouts reached non-finite values")
    assert not data.exists()
    one_line_error(run(["eval", "baseline=tf-full", *TINY], runs, check=False), "gave a non-finite cost")
    assert not (runs / EXP / "eval/tf-full").exists()


def _mount_tmpfs(where: Path, size: str) -> bool:
    """A small tmpfs at ``where`` (root only): a disk that really fills up."""
    where.mkdir(parents=True, exist_ok=True)
    return subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)],
                          capture_output=True).returncode == 0


def _fill(disk: Path, leave_kib: int) -> None:
    """Fill ``disk`` up to ``leave_kib`` KiB of free space."""
    st = os.statvfs(disk)
    free = st.f_bavail * st.f_frsize // 1024
    with open(disk / "filler", "ab") as f:
        f.write(b"\0" * max(0, free - leave_kib) * 1024)


def test_a_write_that_fails_leaves_the_old_file_and_no_temp_file(tmp_path, monkeypatch):
    """The artifact IO layer under a full disk (simulated: every write of a temp file fails with ENOSPC): one
    ArtifactError naming the file, the previous version intact, no temp file left; a pair written together
    (metrics.json and metrics.csv) changes both or neither."""
    import errno

    from neurosym_cli.utils import io

    (tmp_path / "a.json").write_text('{"old": 1}')
    (tmp_path / "a.csv").write_text("old\n")
    real = Path.write_bytes

    def full(self, data):
        if self.name.endswith(".tmp.csv"):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, data)

    monkeypatch.setattr(Path, "write_bytes", full)
    with pytest.raises(ArtifactError, match="no space left on the disk of .*a.csv"):
        io.write_together({tmp_path / "a.json": b'{"new": 1}', tmp_path / "a.csv": b"new\n"})
    assert (tmp_path / "a.json").read_text() == '{"old": 1}' and (tmp_path / "a.csv").read_text() == "old\n"
    with pytest.raises(ArtifactError, match="no space left"):
        io.write_csv(tmp_path / "a.csv", [{"x": 1}])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "a.json"]  # no temp file left


def test_a_disk_that_fills_up_is_one_line_and_nothing_half_written(runs, tmp_path):
    """Issue 28, item 4, on a real 4 MB tmpfs (root only): train and eval stop with one line; nothing that reads
    as complete is half-written; after space is freed the same command finishes."""
    import json

    import torch

    disk = tmp_path / "disk"
    if not _mount_tmpfs(disk, "4m"):
        pytest.skip("needs root to mount a tmpfs (test_a_write_that_fails_... simulates it)")
    try:
        import shutil

        shutil.copytree(runs / EXP / "synth", disk / EXP / "synth")  # no model yet: train must write one
        _fill(disk, 60)  # Hydra's logs fit, the 59 KB checkpoint and its history do not
        one_line_error(run(["train", *TINY], disk, check=False), "no space left on the disk")
        assert not list(disk.rglob("model.pt")) and not list(disk.rglob("*.tmp*"))
        (disk / "filler").unlink()
        run(["train", *TINY], disk)
        assert torch.load(disk / EXP / "train/oracle/model.pt", weights_only=True)["done"]
        for leave in (40, 20, 8):  # the disk fills at another write each time (logs, metrics, figures)
            _fill(disk, leave)
            p = run(["eval", "baseline=tf-full", *TINY], disk, check=False)
            assert "Traceback" not in p.stderr, p.stderr
            if p.returncode:
                assert "no space left on the disk" in p.stderr.strip().splitlines()[-1], p.stderr
            (disk / "filler").unlink()
            for m in disk.rglob("metrics.json"):  # whatever is there reads as a whole evaluation
                assert json.loads(m.read_text())["summary"]["cost"]["mean"] > 0
            assert not list(disk.rglob("*.tmp*"))
    finally:
        subprocess.run(["umount", "-l", str(disk)])


def _read_only(directory: Path) -> Callable[[], None] | None:
    """Make ``directory`` read-only (a read-only bind mount for root, whom permissions do not stop; else the mode
    bits); returns what undoes it, or None when it cannot be done here."""
    if os.geteuid() == 0:
        ok = subprocess.run(["mount", "--bind", str(directory), str(directory)], capture_output=True).returncode == 0
        ok = ok and subprocess.run(["mount", "-o", "remount,ro,bind", str(directory)],
                                   capture_output=True).returncode == 0
        return (lambda: subprocess.run(["umount", "-l", str(directory)])) if ok else None
    modes = {p: p.stat().st_mode for p in [directory, *directory.rglob("*")] if p.is_dir()}
    for p in modes:
        p.chmod(0o555)
    return lambda: [p.chmod(m) for p, m in modes.items()]


def test_a_read_only_seed_directory(runs, tmp_path):
    """Issue 28, item 4: an archived (read-only) seed directory: train and eval stop with one line (whether
    Hydra's logs or our artifacts meet it first), show-program reads it (logging elsewhere), nothing changes."""
    seed = runs / EXP
    before = sorted((p.relative_to(seed), p.stat().st_size) for p in seed.rglob("*") if p.is_file())
    undo = _read_only(seed)
    if undo is None:
        pytest.skip("cannot make a directory read-only here")
    try:
        logs = f"hydra.run.dir={tmp_path / 'logs'}"
        for args in (["train", "overwrite=true"], ["train", "budget.train_rollouts=12"], ["eval", "baseline=tf-full"],
                     ["eval", "baseline=tf-full", logs], ["train", "overwrite=true", logs]):
            one_line_error(run([*args, *TINY], runs, check=False), "read-only")
        assert "random(filter(" in run(["show-program", *TINY, logs], runs).stdout
    finally:
        undo()
    assert sorted((p.relative_to(seed), p.stat().st_size) for p in seed.rglob("*") if p.is_file()) == before


def test_a_team_too_large_for_memory_is_one_line(tmp_path):
    """Issue 28, item 4: a team too large for memory (here under a 4 GB address-space limit) is one line: the
    estimate's refusal before allocating (policy/footprint.py; issue 26) where the machine's free memory is below
    what the team needs, else the allocator's error naming the size asked for and what to make smaller."""
    import resource

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))

    p = run(["train", *TINY, "task.agents_per_group=1500"], tmp_path, check=False, preexec_fn=limit)
    last = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ""
    one_line_error(p, "does not fit" if "does not fit" in last else "out of memory (it asked for")
    assert "the largest team that fits is N =" in last or "a smaller team" in last, p.stderr
    from neurosym_cli.errors import resource_problem

    assert resource_problem(MemoryError()).startswith("out of memory")
    assert resource_problem(ValueError("x")) is None  # a bug keeps its traceback


_MUTATIONS = {
    "a weight missing": lambda p: p["state_dict"].pop(next(iter(p["state_dict"]))),
    "a weight of another shape": lambda p: p["state_dict"].update({next(iter(p["state_dict"])): _zeros(3, 3)}),
    "no architecture": lambda p: p.pop("arch"),
    "an architecture of another type": lambda p: p["arch"].update(obs_dim="x"),
    "an unknown architecture key": lambda p: p["arch"].update(hidden=-5),
    "weights not a dict": lambda p: p.update(state_dict=[1]),
    "no resume state": lambda p: p.pop("fit"),
    "no done flag": lambda p: p.pop("done"),
}


def _zeros(*shape):
    import torch

    return torch.zeros(*shape)


@pytest.mark.parametrize("what", list(_MUTATIONS))
def test_a_checkpoint_with_missing_keys_or_other_shapes_is_refused(trained_root, tmp_path, what):
    """Issue 28, item 4: a checkpoint of the right format tag whose keys are missing or whose weights have other
    shapes is one line at load time (never half-loaded)."""
    import torch

    from neurosym_cli.artifacts import load_checkpoint

    payload = torch.load(trained_root / EXP / "train/oracle/model.pt", weights_only=True)
    _MUTATIONS[what](payload)
    torch.save(payload, tmp_path / "model.pt")
    with pytest.raises(ArtifactError, match="is not a usable checkpoint.*re-run `neurosym train"):
        load_checkpoint(tmp_path / "model.pt", "neurosym train")


def test_a_checkpoint_of_other_shapes_through_the_commands(runs):
    """The same through eval, synth and a resume; and a resume state (Adam's moments) of other shapes."""
    import torch

    ckpt = runs / EXP / "train/oracle/model.pt"
    good = torch.load(ckpt, weights_only=True)
    payload = torch.load(ckpt, weights_only=True)
    _MUTATIONS["a weight of another shape"](payload)
    torch.save(payload, ckpt)
    for verb in (["eval", "baseline=tf-full"], ["synth", "overwrite=true"], ["train", "budget.train_rollouts=12"]):
        one_line_error(run([*verb, *TINY], runs, check=False), "is not a usable checkpoint")
    good["fit"]["optimizer"]["state"][0]["exp_avg"] = torch.zeros(2)
    torch.save(good, ckpt)
    one_line_error(run(["train", *TINY, "budget.train_rollouts=12"], runs, check=False),
                   "its resume state does not fit this model")


@pytest.mark.parametrize("content", ["[1, 2]", '{"rules": "x", "lam": [], "synth": 3}', "not json", '{"a": "b"}'])
def test_corrupt_json_artifacts_name_the_command_that_writes_them_again(runs, content):
    """Issue 28, item 4: metrics.json, selected.json, pipeline_timings.json and summary.json corrupt or of another
    shape or type: one line that names the command writing them again."""
    import dataclasses

    import neurosym_cli.api as ns
    from neurosym_cli.stages.synth import read_summary

    exp = runs / EXP
    (exp / "select").mkdir()
    (exp / "select/selected.json").write_text(content)
    one_line_error(run(["eval", "baseline=prog", "selected=true", *TINY], runs, check=False),
                   "delete it and run `neurosym select task=random-grid budget=tiny seed=0`")
    (exp / "pipeline_timings.json").write_text(content)
    one_line_error(run(["pipeline", "baselines=[tf-full]", *TINY], runs, check=False),
                   "delete it and run `neurosym pipeline task=random-grid budget=tiny seed=0`")
    (exp / "eval/tf-full").mkdir(parents=True)
    (exp / "eval/tf-full/metrics.json").write_text(content)  # read by the table every eval prints
    one_line_error(run(["eval", "baseline=prog", *TINY], runs, check=False),
                   "delete it and run `neurosym pipeline task=random-grid budget=tiny seed=0`")
    (exp / "synth/k2-lam0.5-v1/summary.json").write_text(content)  # select reads every round's time
    cfg = dataclasses.replace(ns.compose("synth", task="random-grid", budget="tiny"), runs_root=str(runs),
                              exp_dir=str(exp))
    with pytest.raises(ArtifactError, match=r"delete it and run `neurosym synth .* overwrite=true`"):
        read_summary(cfg)


@pytest.mark.parametrize("arg,needle", [
    ("seed=${oops}", "${oops} names no key of the config"),
    ("rules=${task.rulez}", "did you mean ${task.rules}?"),
    ("seed=${oc.env:NEUROSYM_SURELY_UNSET}", "NEUROSYM_SURELY_UNSET is not set; set it, or give a default"),
    ("~task", "task cannot be removed"),
    ("~budget", "budget cannot be removed"),
    ("~seed", "seed cannot be removed"),
    ("seed=99999999999999999999", "beyond a 64-bit integer"),
    ("seed=-9223372036854775809", "beyond a 64-bit integer"),
    ("task.v_max=1e308", "task.v_max must lie in"),
    ("hydra.run.dir=${oops}", "Interpolation key 'oops' not found"),  # past our check: Hydra's own, one line
])
def test_interpolations_removals_and_huge_numbers_in_overrides_are_one_line(tmp_path, arg, needle):
    one_line_error(run(["train", *TINY, arg], tmp_path, check=False), needle)
    assert not list(tmp_path.rglob("model.pt"))


@pytest.mark.parametrize("arg", ["task=random-gird", "baseline=tf-ful", "hydra/launcher=nope", "seed=${oops}",
                                 "+foo=1"])
def test_the_python_api_raises_the_console_scripts_line(tmp_path, arg):
    """`ns.compose` refuses bad input with the very line `neurosym train` prints (not Hydra's "Could not find")."""
    import neurosym_cli.api as ns
    from neurosym_cli.errors import UserError

    with pytest.raises(UserError) as e:
        ns.compose("train", [arg, "budget=tiny"])
    p = run(["train", arg, "budget=tiny"], tmp_path, check=False)
    one_line_error(p, str(e.value))
    assert p.stderr.strip() == f"neurosym train: error: {e.value}"


def test_working_interpolations_still_work(tmp_path):
    from neurosym_cli.overrides import check

    os.environ.setdefault("NEUROSYM_RUNS", str(tmp_path))
    assert check(["rules=${task.rules}", "runs_root=${oc.env:NEUROSYM_RUNS}", "seed=${oc.env:NOPE_NOPE,3}",
                  "seed=9223372036854775807"]) is None


@pytest.mark.parametrize("arg", ["lam=" + "9" * 20_000 + "x", "task.name=" + "x" * 20_000, "x" * 20_000 + "=1",
                                 "runs_root=\u00e9" + "x" * 20_000])
def test_long_values_are_cut_in_messages(tmp_path, arg):
    """Issue 28, item 4: a 20,000-character value is quoted in part, with its length; a name that long is refused
    (names are at most 100 characters)."""
    p = run(["train", *TINY, arg], tmp_path, check=False)
    assert p.returncode != 0 and "Traceback" not in p.stderr
    assert len(p.stderr) < 1_000 and "characters)" in p.stderr, p.stderr[:2000]


def test_the_error_edge_cuts_every_long_word():
    from neurosym_cli.errors import cut, cut_words

    msg = cut_words("cannot read " + "/a" * 10_000 + ": gone")
    assert len(msg) < 300 and msg.endswith("... (20,001 characters) gone")  # the word with its colon
    assert cut("short") == "short"


def test_a_byte_order_mark_is_accepted(tmp_path):
    text = "random(filter(d <= 2.0, l))\nrandom(filter(d <= 3.0, l))\n"
    (tmp_path / "bom.txt").write_bytes(b"\xef\xbb\xbf" + text.encode())
    assert load_program(tmp_path / "bom.txt") == parse(text)


def test_a_program_of_20000_rules_is_refused_at_once(tmp_path):
    """Issue 28, item 4: at most 64 rules a round (dsl/parser.MAX_RULES), refused at the 65th line in well under a
    second, where eval would run the whole file for minutes."""
    from neurosym_cli.dsl.parser import MAX_RULES

    big = tmp_path / "big.txt"
    big.write_text("".join(f"random(filter(d <= {k / 1000:.3f}, l))\n" for k in range(20_000)))
    t0 = time.perf_counter()
    with pytest.raises(ArtifactError, match=f"big.txt:{MAX_RULES + 1}:1: round 1 has more than {MAX_RULES} rules"):
        load_program(big)
    assert time.perf_counter() - t0 < 1.0
    assert len(parse("".join(["random(filter(d <= 1.0, l))\n"] * MAX_RULES)).rounds[0]) == MAX_RULES


def test_suggested_commands_quote_paths_with_spaces(runs):
    """Issue 28, item 4: a printed command with a path holding spaces runs as printed (shlex quoting)."""
    import shlex

    folder = runs / "my programs"
    folder.mkdir()
    (folder / "two rules.txt").write_text("random(filter(d <= 2.5, l))\nrandom(filter(d <= 3.0, l))\n")
    p = run(["eval", "baseline=prog-retrained", *TINY, f"program={folder / 'two rules.txt'}"], runs, check=False)
    line = p.stderr.strip().splitlines()[-1]
    printed = line.split("create it with `", 1)[1].rstrip("`")
    assert shlex.quote(f"program={folder / 'two rules.txt'}") in printed
    words = shlex.split(printed)
    assert words[:2] == ["neurosym", "retrain"]
    run([*words[1:], "threads=1"], runs)
    run(["eval", "baseline=prog-retrained", *TINY, f"program={folder / 'two rules.txt'}"], runs)
