"""What a new user hits (issue 28, "the frictions"): persistent defaults, hints that run as printed, "did you mean"
for every way of naming a choice, one-line override grammar errors, no log directories for commands that fail or
only read, help per command."""

import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import neurosym_cmd, run_dir


def run(args, runs, cwd=None, env=None, check=True, timeout=300):
    """The console script in a subprocess with the runs root at ``runs``, persistent defaults unset unless
    ``env`` sets them."""
    base = {k: v for k, v in os.environ.items() if k not in ("NEUROSYM_TASK", "NEUROSYM_BUDGET")}
    p = subprocess.run([*neurosym_cmd(), *args], cwd=cwd or runs, env={**base, "NEUROSYM_RUNS": str(runs), **(env or {})},
                       capture_output=True, text=True, timeout=timeout)
    if check and p.returncode != 0:
        raise AssertionError(f"exit {p.returncode}\nstdout:\n{p.stdout}\nstderr:\n{p.stderr}")
    return p


def one_line(p, needle):
    assert p.returncode != 0, p.stdout
    assert "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert needle in p.stderr, p.stderr


# ------------------------------------------------------------------------------------- persistent defaults
def test_task_and_budget_defaults_from_environment_and_project_file(tmp_path):
    (tmp_path / "neurosym.yaml").write_text("budget: tiny\ntask: two-groups-cross\n")
    p = run(["train", "threads=1"], tmp_path, env={"NEUROSYM_TASK": "random-grid"})
    assert (tmp_path / "random-grid/tiny/seed0/train/oracle/model.pt").exists()  # environment > file
    assert f"task=random-grid (from NEUROSYM_TASK) budget=tiny (from {tmp_path / 'neurosym.yaml'})" in p.stdout
    p = run(["eval", "baseline=tf-full", "task=two-groups-cross", "threads=1"], tmp_path, check=False,
            env={"NEUROSYM_TASK": "random-grid"})  # the command line wins over both
    one_line(p, "neurosym train task=two-groups-cross baseline=tf-full budget=tiny")
    p = run(["train", "threads=1"], tmp_path, env={"NEUROSYM_TASK": "random-grd"}, check=False)
    one_line(p, "unknown task 'random-grd' (the default set by NEUROSYM_TASK); did you mean task=random-grid?")
    (tmp_path / "neurosym.yaml").write_text("budgett: tiny\n")
    one_line(run(["train"], tmp_path, check=False), "neurosym.yaml: unknown key 'budgett'; it may set task and budget")
    (tmp_path / ".neurosym.yaml").write_text("task: random-grid\n")
    one_line(run(["train"], tmp_path, check=False), "hold neurosym defaults; keep one")


# ------------------------------------------------------------------------------------ hints run as printed
def hints(p) -> list[list[str]]:
    """Every `neurosym ...` command a run printed (stdout and stderr; rich wraps long lines at spaces)."""
    import re

    text = " ".join((p.stdout + "\n" + p.stderr).split())
    return [shlex.split(c)[1:] for c in re.findall(r"`(neurosym [^`]+)`", text) if "..." not in c]


def run_hint(args, cwd):
    """A printed command, run as printed from another directory, no runs root or defaults in the environment."""
    env = {k: v for k, v in os.environ.items() if k not in ("NEUROSYM_RUNS", "NEUROSYM_TASK", "NEUROSYM_BUDGET")}
    p = subprocess.run([*neurosym_cmd(), *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, f"hint `neurosym {shlex.join(args)}` failed:\n{p.stdout}\n{p.stderr}"
    return p


@pytest.mark.slow
def test_every_printed_hint_runs_as_printed(tmp_path):
    runs, elsewhere = tmp_path / "my runs", tmp_path / "elsewhere"
    elsewhere.mkdir()
    common = ["task=two-groups-cross", "budget=tiny", f"runs_root={runs}"]
    p = run(["eval", "baseline=hard-attn", *common], tmp_path, check=False)
    (train,) = hints(p)
    assert train[0] == "train" and f"runs_root={runs}" in train
    run_hint(train, elsewhere)
    run(["eval", "baseline=hard-attn", *common], tmp_path)
    p = run(["select", *common, "select.lam=[0.5]", "select.rules=[1]", "select.features=[v1]",
             "select.finalists=1", "budget.val_seeds=2", "select.jobs=1"], tmp_path)
    *guard, evaluate, pipeline = hints(p)  # the guard's line first where the tiny program is silent or no better
    assert [evaluate[0], pipeline[0]] == ["eval", "pipeline"]
    assert "selected=true" in evaluate and "selected=true" in pipeline
    assert "budget=tiny" in evaluate
    assert all(h[0] == "show-program" and f"runs_root={runs}" in h for h in guard), guard  # it prints the front
    for h in (*guard, evaluate, pipeline):
        run_hint(h, elsewhere)
    p = run(["stress", "task=random-grid", "budget=tiny", f"runs_root={runs}"], tmp_path, check=False)
    pipeline = hints(p)[-1]  # the closing line's: the warnings before it name each missing model's command
    assert pipeline[0] == "pipeline" and "stress" in p.stderr.strip().splitlines()[-1]
    p = run(["report", f"report_dir={runs / 'random-grid/tiny'}"], tmp_path, check=False)
    (pipeline,) = hints(p)  # the same pipeline, for every seed's directory of the report
    assert pipeline[:3] == ["pipeline", "task=random-grid", "budget=tiny"] and f"runs_root={runs}" in pipeline
    run_hint(pipeline, elsewhere)
    run(["report", f"report_dir={runs / 'random-grid/tiny'}", "report.reps=100", "plots=false"], tmp_path)


# ------------------------------------------------------------------------------- did you mean, one line each
@pytest.mark.parametrize("args,needle", [
    (["random-grid"], "'random-grid' is not an override; did you mean task=random-grid?"),
    (["tiny"], "did you mean budget=tiny?"),
    (["random-grd"], "did you mean task=random-grid?"),
    (["--task", "random-grid"], "--task random-grid: settings are key=value; did you mean task=random-grid?"),
    (["--task=random-grd"], "did you mean task=random-grid?"),
    (["--budget", "tiny"], "did you mean budget=tiny?"),
    (["--seed", "3"], "did you mean seed=3?"),
    (["rules", "3"], "did you mean rules=3?"),
    (["--colour"], "unknown flag --colour; settings are key=value"),
    (["task=random-grd"], "unknown task 'random-grd'; did you mean task=random-grid?"),
    (["baseline=hard-atn"], "did you mean baseline=hard-attn?"),
    (["rules=[1,2"], "cannot read '[1,2' at '['; a list is [a,b] with its brackets closed"),
    (["select.rules=[1,x]"], "select.rules takes a list of integers"),
    (["seed=null"], "seed cannot be null; it takes an integer"),
    (["seed=[1,2]"], "seed takes one value (an integer), not a list"),
    (["rules='\u00e9'"], "rules takes an integer"),
    (["hydra/launcher=nope"], "unknown hydra/launcher 'nope' (choices: basic, joblib, slurm"),
    (["hydra/launcher=jobib"], "did you mean hydra/launcher=joblib?"),
    (["task=random-grid,random-cross"], "a comma makes a sweep (add -m)"),
])
def test_mistyped_arguments_are_one_line_with_the_fix(tmp_path, args, needle):
    p = run(["train", *args], tmp_path, check=False)
    one_line(p, needle)
    assert not (tmp_path / "random-cross").exists()


@pytest.mark.parametrize("name", ["a;b.txt", "a,b.txt", "a=b.txt", "it's.txt", "a[b].txt", "$(touch pwned).txt",
                                  "caf\u00e9 \u00e0 deux.txt"])
def test_program_file_names_hydra_cannot_read_get_the_quoting_that_works(tmp_path, name):
    (tmp_path / name).write_text("argmax(map(-1.0*d, filter(d <= 2.0, l)))\n")
    p = run(["show-program", "task=random-grid", f"program={name}"], tmp_path, check=False)
    if p.returncode == 0:  # Hydra reads a few such names as they are
        assert "argmax" in p.stdout
        return
    assert "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    typed = p.stderr.strip().rsplit(": ", 1)[1].rsplit("quote it ", 1)[-1]
    (arg,) = shlex.split(typed)  # what the shell passes when the printed text is typed
    p = run(["show-program", "task=random-grid", arg], tmp_path)
    assert "argmax" in p.stdout and not (tmp_path / "pwned").exists()


# ------------------------------------------------------------------------ no traces of failed or reading runs
def test_failed_and_read_only_commands_leave_no_directories(tmp_path):
    for args in (["synth", "task=random-grid", "budget=tiny"], ["eval", "task=random-grid", "budget=tiny"],
                 ["train", "task=random-grid", "budget=tiny", "lam=-1"], ["show-program"], ["report"],
                 ["report", f"report_dir={tmp_path / 'random-grid/tiny'}"]):
        p = run(args, tmp_path, check=False)
        assert p.returncode != 0 and "Traceback" not in p.stderr, p.stderr
        assert sorted(tmp_path.rglob("*")) == [], (args, sorted(tmp_path.rglob("*")))
    run(["train", "task=random-grid", "budget=tiny", "threads=1"], tmp_path)
    exp = tmp_path / "random-grid/tiny/seed0"
    assert len(list((exp / "logs").iterdir())) == 1  # a command that ran keeps its log
    (tmp_path / "p.txt").write_text("random(filter(d <= 2.0, l))\n")
    run(["show-program", "task=random-grid", "budget=tiny", "program=p.txt"], tmp_path)
    p = run(["retrain", "task=random-grid", "budget=tiny"], tmp_path, check=False)  # no program: nothing written
    assert p.returncode != 0 and len(list((exp / "logs").iterdir())) == 1 and not (exp / "synth").exists()
    assert sorted(d.name for d in exp.iterdir()) == ["logs", "train"]


# ----------------------------------------------------------------------------------------- help per command
def test_help_per_command_has_the_schema_docstrings_and_only_its_sections(tmp_path):
    p = run(["train", "--help", "task=random-grid"], tmp_path)
    out = p.stdout
    assert "optim.lr=0.01" in out and "Adam learning rate at the start" in out  # value and docstring
    assert "task (random-grid, GridConfig)" in out and "seed=0" in out and "training seed" in out
    budgets = sorted(f.stem for f in (Path(__file__).parents[1] / "conf/budget").glob("*.yaml"))
    assert "budget    " + ", ".join(b + "*" * (b == "quick") for b in budgets) in out  # every group option
    assert "baseline  tf-full*" in out
    assert "select." not in out and "report." not in out and "render." not in out and "hydra" not in out
    assert len(out.splitlines()) < 130 and not list(tmp_path.iterdir())
    out = run(["report", "-h"], tmp_path).stdout
    assert "report.reps=50000" in out and "bootstrap resamples" in out and "report_dir=''" in out
    assert "optim." not in out and "task.horizon" not in out and "baseline " not in out
    out = run(["select", "--help"], tmp_path).stdout
    assert "select.lam=[]" in out and "synth.coarse=4" in out  # the command's own defaults (lam: the objective's)
    code = ("import sys; sys.argv=['neurosym','synth','--help']; from neurosym_cli.cli import main; main(); "
            "assert 'torch' not in sys.modules, 'torch imported'")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 0 and "synth.temperature=0.1" in p.stdout, p.stderr


# ------------------------------------------------------------------- one word per degree, labels that differ
def test_one_word_per_degree_with_a_legend_under_every_table(tmp_path):
    from neurosym_cli.degrees import LEGEND

    run(["train", "task=random-grid", "budget=tiny", "threads=1"], tmp_path)
    p = run(["eval", "task=random-grid", "budget=tiny", "baseline=hard-attn", "plots=false"], tmp_path)
    words = " ".join(p.stdout.replace("│", " ").replace("┃", " ").split())
    # the bandwidth columns after mean in+out (issue 40: degrees.BANDWIDTH)
    assert "max in max out max in+out mean in+out bits/agent/step link share collisions" in words
    assert " ".join(LEGEND.split()) in words
    assert "mean deg" not in words and "max deg" not in words and "in-deg " not in words
    p = run(["synth", "task=random-grid", "budget=tiny", "threads=1", "progress=plain"], tmp_path)
    assert "x max in+out" in p.stdout and "degree term" not in p.stdout
    assert "max in+out: the program's max_i (in_i + out_i) on the synthesis dataset D" in p.stdout
    p = run(["show-program", "task=random-grid", "budget=tiny"], tmp_path)
    words = " ".join(p.stdout.replace("│", " ").split())
    assert "x max in+out" in words and "max in+out ≤" in words and "x degree" not in words


def test_labels_tell_configurations_apart_and_numbers_keep_their_decimals(tmp_path, caplog):
    import logging

    from neurosym_cli.commands.sweep import _cell
    from neurosym_cli.plotting import short_labels
    from neurosym_cli.stages.results import write_pareto

    assert short_labels(["tf-full", "prog-k2-lam0.5-v1", "prog-k3-lam0.5-v1", "rl1", "rl2"]) == \
        ["tf-full", "prog-k2", "prog-k3", "rl1", "rl2"]
    assert short_labels(["prog-k2-lam0.3-v1", "prog-k2-lam0.5-v1"]) == ["prog-lam0.3", "prog-lam0.5"]
    assert _cell(413.806) == "413.806" and _cell(1413.8) == "1413.800" and _cell(None) == "-" and _cell(3) == "3"
    rows = [(label, {"max_degree": {"mean": x}, "cost": {"mean": y}})
            for label, x, y in (("a", 5.0, 1.0), ("b", 1.0, 2.0), ("c", 6.0, 3.0))]
    with caplog.at_level(logging.INFO, logger="neurosym"):
        write_pareto(rows, tmp_path, "t", plot=False)
    assert "non-dominated (loss, max in+out), lowest loss first: a (1.000, 5.000), b (2.000, 1.000)" in caplog.text


def test_the_results_page_shows_programs_simplified():
    """docs/results.md (benchmarks/results_doc.py) shows each committed program through the data-free
    simplification: no test on a distance below zero, no one-feature `or` that always holds."""
    import re

    page = (Path(__file__).resolve().parents[1] / "docs/results.md").read_text()
    code = "\n".join(re.findall(r"```[a-z]*\n(.*?)```", page, flags=re.S))
    assert "argmax(map(" in code and "Shown simplified" in page
    assert not re.search(r"\b(d|gd|pd|g\d+d) <= -", code), "a test no distance passes"
    for f, a, b in re.findall(r"(\w+) <= (-?[\d.]+) or \1 >= (-?[\d.]+)", code):
        assert float(a) < float(b), f"`{f} <= {a} or {f} >= {b}` always holds"


# -------------------------------------------------------------------------- select and a sweep's programs
@pytest.mark.slow
def test_select_names_the_command_that_reuses_a_sweeps_programs_and_that_command_does(tmp_path):
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.stages.select import grid, searched_otherwise

    common = ["task=two-groups-cross", "budget=tiny", "threads=1"]
    run(["train", *common], tmp_path)
    run(["synth", "-m", "rules=1,2", "lam=0.5", *common], tmp_path)
    synth = tmp_path / "two-groups-cross/tiny/seed0/synth"
    swept = sorted(p.name for p in synth.iterdir() if p.is_dir())
    tags = [run_dir("synth", tmp_path, *common, f"rules={k}", "lam=0.5").program_tag for k in (1, 2)]  # synth's
    assert tags[0].startswith("k1-lam0.5-v1") and tags[1].startswith("k2-lam0.5-v1")  # and the default search's
    assert swept == tags
    cfg = compose_config("select", [f"runs_root={tmp_path}", *common, "select.lam=[0.5]", "select.rules=[1,2]",
                                    "select.features=[v1]"])
    line = searched_otherwise(cfg, grid(cfg))
    assert line and f"2 of the 2 grid programs exist searched with other settings ({tags[0]}, {tags[1]})" in line
    (hint,) = hints(subprocess.CompletedProcess([], 0, line, ""))
    assert "synth.coarse=1" in hint and "synth.patience=0" in hint
    p = run([*hint, "budget.val_seeds=2", "select.finalists=1", "select.jobs=1"], tmp_path)
    assert sorted(p.name for p in synth.iterdir() if p.is_dir()) == swept  # nothing searched again
    assert "already synthesized" in p.stdout
    assert compose_config("select", [f"runs_root={tmp_path}", *hint[1:]]).synth.coarse == 1
