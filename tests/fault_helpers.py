"""What the fault tests (tests/test_faults_*.py) share: running the console script, the one-line-error check,
a good program and the tiny random-grid run they probe."""

import os
import subprocess

from conftest import neurosym_cmd


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


GOOD = "argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nrandom(filter(d >= 3.41 and gd <= 2.0, l))\n"
EXP = "random-grid/tiny/seed0"
TINY = ["task=random-grid", "budget=tiny", "threads=1"]
