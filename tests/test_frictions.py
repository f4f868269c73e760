"""What a new user hits (issue 28, "the frictions"): persistent defaults, hints that run as printed, "did you mean"
for every way of naming a choice, one-line override grammar errors, no log directories for commands that fail or
only read, help per command."""

import os
import shlex
import subprocess

from conftest import neurosym_cmd


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
