"""The pipeline one stage after the other against its stages at once (`pipeline.jobs`, docs/performance.md 19).

    python benchmarks/bench_pipeline_jobs.py                                   # the README's main job, jobs 1 and 0
    python benchmarks/bench_pipeline_jobs.py --args task=random-grid budget=tiny --jobs 1 2
    python benchmarks/bench_pipeline_jobs.py --before /tmp/old/.venv/bin/neurosym   # first the same command as an
                                                                                     # older install runs it

Runs `neurosym pipeline <args> pipeline.jobs=J` for each J in a fresh runs root of its own (nothing reused), one
after the other on this machine (pause other work: the ratio is what is measured), and prints each wall time, its
ratio to the first, the sum of the stages' own times (pipeline_timings.json) and whether every artifact's numbers
equal the first run's (benchmarks/fingerprint.py). With ``--before``, the same command first runs under another
install's ``neurosym`` (for example a worktree of the commit before a change, with its own defaults and without
``pipeline.jobs``), and every ratio is to that run: "today's wall time" of an issue measured on the same machine.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks.fingerprint import fingerprint  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--args", nargs="*", default=["task=two-groups-cross"], help="the pipeline's overrides")
    ap.add_argument("--jobs", nargs="+", type=int, default=[1, 0], help="pipeline.jobs values (0: one per core)")
    ap.add_argument("--before", default="", help="another install's neurosym: its run of the same command first, "
                    "the reference of every ratio (its artifacts are not compared: another version's pipeline)")
    ap.add_argument("--keep", default="", help="keep the runs roots under this directory (default: a temporary one)")
    a = ap.parse_args()
    exe = Path(sys.executable).parent / "neurosym"
    root = Path(a.keep or tempfile.mkdtemp(prefix="bench-pipeline-jobs-"))
    if a.keep and root.exists() and any(root.iterdir()):  # a pipeline reuses what it finds: not a fresh run
        sys.exit(f"--keep {root} is not empty: give a new folder (every run must start from nothing)")
    env = {k: v for k, v in os.environ.items() if k != "NEUROSYM_PIPELINE_JOBS"}
    print(f"neurosym pipeline {' '.join(a.args)}; {os.cpu_count()} CPU(s); runs under {root}")
    before = None
    if a.before:
        wall, stages = _run([a.before, "pipeline", *a.args, f"runs_root={root / 'before'}", "progress=plain"],
                            env, root / "before", "--before")
        before = wall
        print(f"{a.before}: {wall:7.1f} s wall, the reference; stages' own times {stages:.0f} s")
    first = None
    for jobs in a.jobs:
        runs = root / f"jobs{jobs}"
        cmd = [str(exe), "pipeline", *a.args, f"runs_root={runs}", f"pipeline.jobs={jobs}", "progress=plain"]
        wall, stages = _run(cmd, env, runs, f"pipeline.jobs={jobs}")
        prints = fingerprint(runs)
        first = first or (wall, prints)
        same = "same numbers" if prints == first[1] else \
            f"{sum(first[1].get(k) != v for k, v in prints.items())} of {len(prints)} artifacts differ"
        print(f"pipeline.jobs={jobs}: {wall:7.1f} s wall, {wall / (before or first[0]):.2f} of the "
              f"{'--before run' if before else 'first'}; stages' own times {stages:.0f} s; {len(prints)} artifacts, "
              f"{same}")


def _run(cmd: list[str], env: dict, runs: Path, what: str) -> tuple[float, float]:
    """Run one pipeline command -> its wall seconds and the sum of its stages' own seconds (pipeline_timings.json)."""
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit(f"{what} failed (exit {p.returncode}): {p.stderr.strip()[-500:]}")
    return wall, sum(sum(json.loads(f.read_text()).values()) for f in runs.rglob("pipeline_timings.json"))


if __name__ == "__main__":
    main()
