"""Training beside other busy processes: wall time of one training run per thread setting, alone and with
competitors (issue 39, "a default that does not collapse under contention").

    python benchmarks/bench_contention.py                       # 200 rollouts of random-cross, 0 and 3 competitors
    python benchmarks/bench_contention.py --competitors 0 1 3 --rollouts 400 --repeats 2

Each row runs `neurosym train task=random-cross` (B = 50, the quick budget's batch, a fresh runs root) in a child
process while `--competitors` pure-Python busy loops hold the cores, and prints the wall seconds and each setting's
ratio to the default (threads=1). The settings:

    threads=0 spin      torch's default team (one thread per core) whose idle threads spin (OMP_WAIT_POLICY=ACTIVE)
    threads=0 passive   the same team, idle threads sleep (OMP_WAIT_POLICY=PASSIVE, what neurosym sets unless a user
                        set it: utils/cpu.py)
    threads=1           the default since issue 39

Ratios, not seconds, are the result: the machine is shared and the seconds move with its load.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

SETTINGS = {
    "threads=0 spin": ("threads=0", "ACTIVE"),
    "threads=0 passive": ("threads=0", "PASSIVE"),
    "threads=1": ("threads=1", "PASSIVE"),
}
"""row label -> (the threads override, OMP_WAIT_POLICY)"""
BUSY = "while True: pass"


def one_run(threads: str, policy: str, *, competitors: int, rollouts: int) -> float:
    """Wall seconds of one training run of ``rollouts`` rollouts beside ``competitors`` busy loops."""
    busy = [subprocess.Popen([sys.executable, "-c", BUSY]) for _ in range(competitors)]
    try:
        with tempfile.TemporaryDirectory() as root:
            env = {**os.environ, "OMP_WAIT_POLICY": policy}
            argv = [sys.executable, "-m", "neurosym_cli.cli", "train", "task=random-cross", "budget=tiny",
                    f"budget.train_rollouts={rollouts}", "budget.batch_rollouts=50", threads, "plots=false",
                    f"runs_root={root}"]
            t0 = time.perf_counter()
            p = subprocess.run(argv, env=env, capture_output=True, text=True)
            wall = time.perf_counter() - t0
            if p.returncode != 0:
                raise SystemExit(f"training failed ({threads}, {policy}): {p.stderr.strip().splitlines()[-1:]}")
            return wall
    finally:
        for b in busy:
            b.kill()
            b.wait()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--competitors", type=int, nargs="+", default=[0, 3], help="busy processes beside the run")
    ap.add_argument("--rollouts", type=int, default=200, help="training rollouts per run (batches of 50)")
    ap.add_argument("--repeats", type=int, default=1, help="runs per cell; the median is printed")
    a = ap.parse_args()
    print(f"{os.cpu_count()} CPUs; random-cross training, {a.rollouts} rollouts in batches of 50; wall seconds "
          f"(median of {a.repeats})")
    for c in a.competitors:
        walls = {}
        for label, (threads, policy) in SETTINGS.items():
            runs = sorted(one_run(threads, policy, competitors=c, rollouts=a.rollouts) for _ in range(a.repeats))
            walls[label] = runs[len(runs) // 2]
        base = walls["threads=1"]
        cells = "  ".join(f"{k}: {v:6.1f} s ({v / base:4.2f}x)" for k, v in walls.items())
        print(f"{c} competitors  {cells}")


if __name__ == "__main__":
    main()
