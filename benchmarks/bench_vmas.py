"""Training and evaluation rollouts/s through VMAS against a native task at the same N, and where the time goes.

    python benchmarks/bench_vmas.py                        # N = 4 and 8, B = 8, T = 30 (a few minutes)
    python benchmarks/bench_vmas.py --sizes 4 8 16 --json docs/results/bench-vmas.json
    python benchmarks/bench_vmas.py --sizes 6 --tasks vmas-navigation vmas-nolidar vmas-dispersion ring

Tasks, each at team size N: ``vmas/navigation`` as shipped (VMAS's own observation, 12 lidar rays, contact
forces), the same without the scenario's observation (``scenario_obs=false``: no lidar, the task
vmas/navigation-nolidar), ``vmas/dispersion`` (``--tasks vmas-dispersion``: its observation lists every food
item; no lidar, no collisions), and the native ring (examples/ring: single-integrator agents, the same
transformer widths but for Ds). Training = forward and backward of B episodes of T steps with full soft
attention (the oracle's step); evaluation = the same rollout under no_grad with the metrics. Time per part
comes from wrapping the task's methods (observe, step, cost) and timing the policy's forward and the backward
separately; VMAS's share of step is the simulator itself.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import defaultdict
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples" / "ring"))

from neurosym_cli.commands.apps import compose_config  # noqa: E402
from neurosym_cli.config import ModelConfig  # noqa: E402
from neurosym_cli.policy import CommTransformer, FullComm  # noqa: E402
from neurosym_cli.rollout import rollout  # noqa: E402
from neurosym_cli.tasks import Rng, make_task  # noqa: E402


class Timed:
    """The task with its observe/step/cost timed (seconds accumulated per method)."""

    def __init__(self, task, clock):
        self._task, self._clock = task, clock

    def __getattr__(self, name):
        fn = getattr(self._task, name)
        if name not in ("observe", "step", "cost") or not callable(fn):
            return fn

        def timed(*a, **k):
            t0 = time.perf_counter()
            out = fn(*a, **k)
            self._clock[name] += time.perf_counter() - t0
            return out

        return timed


def make(kind: str, n: int, horizon: int):
    if kind == "ring":
        import ring

        return make_task(ring.RingConfig(agents_per_group=n), horizon)
    scenario = "dispersion" if kind == "vmas-dispersion" else "navigation"
    over = [f"task=vmas/{scenario}", f"task.team_sizes=[{n}]", f"task.test_sizes=[{n}]"]
    if kind == "vmas-dispersion":
        over.append(f"task.agents_per_group={n}")
    if kind == "vmas-nolidar":
        over.append("task.scenario_obs=false")
    return make_task(compose_config("train", over).task, horizon)


def measure(kind: str, n: int, batch: int, horizon: int, repeats: int) -> dict:
    task = make(kind, n, horizon)
    torch.manual_seed(0)
    pol = CommTransformer.for_task(task, ModelConfig(dropout=0.0))
    gen = torch.Generator().manual_seed(0)
    task.reset(batch, gen)  # builds the VMAS instance of this bucket shape (not timed)
    out: dict = {"task": kind, "N": n, "B": batch, "T": horizon}
    for mode in ("train", "eval"):
        best, parts = float("inf"), {}
        for _ in range(repeats):
            clock: dict = defaultdict(float)
            timed = Timed(task, clock)
            s = task.reset(batch, gen)[0]
            t0 = time.perf_counter()
            if mode == "train":
                traj = rollout(timed, pol, FullComm(), s, Rng(gen), horizon, stats=False)
                t1 = time.perf_counter()
                traj.cost.sum().backward()
                clock["backward"] = time.perf_counter() - t1
            else:
                with torch.no_grad():
                    rollout(timed, pol, FullComm(), s, Rng(gen), horizon, stats=True)
            total = time.perf_counter() - t0
            if total < best:
                best = total
                parts = {k: round(v, 4) for k, v in clock.items()}
                parts["policy+rest"] = round(total - sum(clock.values()), 4)
        out[mode] = {"seconds": round(best, 4), "rollouts_per_s": round(batch / best, 2), "parts_s": parts}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[4, 8])
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--horizon", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--tasks", nargs="+", default=["vmas-navigation", "vmas-nolidar", "ring"],
                    choices=["vmas-navigation", "vmas-nolidar", "vmas-dispersion", "ring"])
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    rows = [measure(k, n, a.batch, a.horizon, a.repeats) for n in a.sizes
            for k in a.tasks]
    print(f"B = {a.batch}, T = {a.horizon}, {a.threads} thread(s), best of {a.repeats}")
    print("| task | N | train rollouts/s | eval rollouts/s | train: observe / step / cost / backward / policy+rest (s) |")
    print("|---|---:|---:|---:|---|")
    for r in rows:
        p = r["train"]["parts_s"]
        split = " / ".join(f"{p.get(k, 0):.2f}" for k in ("observe", "step", "cost", "backward", "policy+rest"))
        print(f"| {r['task']} | {r['N']} | {r['train']['rollouts_per_s']:.2f} | {r['eval']['rollouts_per_s']:.2f} "
              f"| {split} |")
    if a.json:
        a.json.parent.mkdir(parents=True, exist_ok=True)
        a.json.write_text(json.dumps({"batch": a.batch, "horizon": a.horizon, "threads": a.threads, "rows": rows},
                                     indent=1))


if __name__ == "__main__":
    main()
