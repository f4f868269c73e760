"""Issue 38, interrupted and odd files: a Ctrl-C between a program and its summary, a summary.json of another shape,
a run lock that is a directory, a sweep directory outside the runs root, a huge defaults file."""

import json
import shutil
import time

import pytest

from fault_helpers import GOOD, TINY, run
from test_plugins import one_line

EXP = "random-grid/tiny/seed0"


@pytest.fixture(scope="module")
def synthesized(tmp_path_factory):
    """A tiny random-grid run root with the oracle trained and its program searched (copied by each test)."""
    root = tmp_path_factory.mktemp("synthesized")
    run(["train", *TINY, "plots=false"], root)
    run(["synth", *TINY], root)
    return root


@pytest.fixture
def runs(synthesized, tmp_path):
    shutil.copytree(synthesized, tmp_path, dirs_exist_ok=True)
    return tmp_path


def _synth_cfg(runs, **kw):
    import neurosym_cli.api as ns

    return ns.compose("synth", task="random-grid", budget="tiny", threads=1, runs_root=str(runs), **kw)


def _synth_dir(runs, **kw):
    """synth/<tag> of the search `neurosym synth` makes (its tag: K, lambda, features, the default search's)."""
    from neurosym_cli.run import RunDir

    return RunDir(_synth_cfg(runs, **kw)).synth_dir


@pytest.mark.parametrize("stop_at", ["write_csv", "write_json"])
def test_a_ctrl_c_between_the_writes_never_leaves_a_program_without_its_summary(runs, monkeypatch, stop_at):
    """The program was written first: a Ctrl-C before summary.json left it alone (or beside the old search's
    summary), and eval, retrain and show-program used it. Now the program comes last: interrupted, there is none,
    and synth searches again."""
    import neurosym_cli.stages.synth as synth
    from neurosym_cli.stages import RunInfo

    out = _synth_dir(runs)
    before = (out / "program.txt").read_text()

    def interrupt(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(synth, stop_at, interrupt)
    with pytest.raises(KeyboardInterrupt):  # overwrite=true: the old program and summary are there
        synth.synthesize(_synth_cfg(runs, overwrite=True), RunInfo(multirun=True))
    monkeypatch.undo()
    assert not (out / "program.txt").exists()
    p = run(["synth", *TINY], runs)  # not "already synthesized": the search runs again, and ends as before
    assert "already synthesized" not in p.stdout and (out / "program.txt").read_text() == before
    assert json.loads((out / "summary.json").read_text())["program"] in before


def test_a_program_without_its_search_summary_is_refused_by_the_verbs_that_run_it(runs):
    """A program.txt alone (an older version's Ctrl-C) or beside another search's summary: one line naming the
    search that remakes it; show-program shows its rules without terms and says why; synth searches it again."""
    out = _synth_dir(runs)
    summary = (out / "summary.json").read_text()
    (out / "summary.json").unlink()
    for verb in (["eval", "baseline=prog"], ["retrain"], ["render", "baseline=prog"]):
        line = one_line(run([*verb, *TINY], runs, check=False))
        assert "program.txt has no summary.json beside it" in line and "neurosym synth" in line, line
        assert "overwrite=true" in line and "program=PATH" in line, line
    p = run(["show-program", *TINY], runs)
    assert "argmax" in p.stdout or "random" in p.stdout
    assert "has no summary.json beside it" in p.stderr + p.stdout and "L1 action error" not in p.stdout
    (out / "summary.json").write_text(summary)
    (out / "program.txt").write_text(GOOD)  # not the program its summary records
    line = one_line(run(["eval", "baseline=prog", *TINY], runs, check=False))
    assert "is not the program its summary.json records" in line and "overwrite=true" in line, line
    p = run(["synth", *TINY], runs, check=False)  # never "already synthesized" over a half
    assert p.returncode != 0 and "is not the program its summary.json records" in p.stderr
    # a program of the user's own, given with program=, needs no summary
    mine = runs / "mine.txt"
    mine.write_text(GOOD)
    run(["show-program", *TINY, f"program={mine}"], runs)


def _round(summary: dict, **change) -> dict:
    out = json.loads(json.dumps(summary))
    for key, value in change.items():
        if key == "top":
            return value
        path = key.split("__")
        node = out
        for k in path[:-1]:
            node = node[int(k)] if isinstance(node, list) else node[k]
        node[int(path[-1]) if isinstance(node, list) else path[-1]] = value
    return out


SHAPES = {
    "a list": dict(top=[1, 2]),
    "no rounds": dict(rounds="x"),
    "simplified a number": dict(rounds__0__simplified=5),
    "fires a string": dict(rounds__0__rule_stats__0__fires="x"),
    "flags a number": dict(rounds__0__rule_stats__0__flags=3),
    "hall of fame rows of numbers": dict(rounds__0__hall_of_fame={"complexity": [5], "degree": [[1]]}),
    "hall of fame fields of other types": dict(rounds__0__hall_of_fame={"complexity": [{"level": [], "objective": "a"}]}),
    "config a list": dict(config=[1]),
    "an unknown objective": dict(config={"synth": {"objective": "nope"}}),
    "lam a string": dict(lam="x"),
}


def test_show_program_reads_summaries_of_any_shape_without_a_traceback(runs):
    """rule_stats, simplified, hall_of_fame and config of other types were a traceback; the whole summary of
    another shape is now one warning line naming the search that writes it again."""
    out = _synth_dir(runs)
    good = json.loads((out / "summary.json").read_text())
    for name, change in SHAPES.items():
        (out / "summary.json").write_text(json.dumps(_round(good, **change)))
        p = run(["show-program", *TINY], runs, check=False)
        assert p.returncode == 0 and "Traceback" not in p.stderr + p.stdout, (name, p.stderr)
        assert "argmax" in p.stdout or "random" in p.stdout, name
    (out / "summary.json").write_text("[1, 2]")
    p = run(["show-program", *TINY], runs)
    warning = [ln for ln in p.stderr.splitlines() + p.stdout.splitlines() if "not of the shape synth writes" in ln]
    assert warning and "overwrite=true" in " ".join(p.stdout.split() + p.stderr.split()), p.stdout + p.stderr


def test_a_run_lock_that_is_a_directory_is_one_line(runs):
    """A directory named .lock where the lock file goes: it said 'cannot write to <dir>: Is a directory', naming
    the wrong path; now it names the lock and what to do."""
    lock = runs / EXP / "train/oracle/.lock"
    lock.unlink()
    lock.mkdir()
    line = one_line(run(["train", *TINY, "plots=false", "overwrite=true"], runs, check=False))
    assert f"{lock} is a directory" in line and "rmdir" in line, line
    assert lock.is_dir() and (runs / EXP / "train/oracle/model.pt").exists()  # nothing lost


def test_a_sweep_directory_outside_the_runs_root_runs_every_job(runs, tmp_path_factory):
    """Hydra's sweep.dir elsewhere: the first job confined writes to its own directory, and every later job's
    record was refused with a traceback."""
    elsewhere = tmp_path_factory.mktemp("elsewhere") / "sweep"
    p = run(["synth", "-m", *TINY, "lam=0.5,0.7", f"hydra.sweep.dir={elsewhere}"], runs, check=False)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    results = sorted(elsewhere.glob("*/job_result.json"))
    assert len(results) == 2 and all(json.loads(r.read_text())["ok"] for r in results)
    assert (_synth_dir(runs, lam=0.7) / "program.txt").exists()


def test_a_huge_defaults_file_is_refused_before_it_is_parsed(tmp_path):
    """A 25 MB neurosym.yaml took over a minute and 2.4 GB; a defaults file holds two names."""
    (tmp_path / "neurosym.yaml").write_text("task: random-grid\n" + "# " + "x" * 2_000_000 + "\n")
    start = time.time()
    line = one_line(run(["train", "budget=tiny"], tmp_path, check=False, timeout=60))
    assert time.time() - start < 30
    assert "neurosym.yaml" in line and "2.0 MB" in line and "task: random-grid" in line, line
    from neurosym_cli.defaults import DefaultsError, read_project_file

    with pytest.raises(DefaultsError, match="more than"):
        read_project_file(tmp_path / "neurosym.yaml")
    (tmp_path / "neurosym.yaml").write_text("task: random-grid\n")
    assert read_project_file(tmp_path / "neurosym.yaml") == {"task": "random-grid"}
