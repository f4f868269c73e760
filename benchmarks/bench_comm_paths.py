"""Training step cost under each communication provider: the dense path (all N^2 pairs scored, then masked) vs
the sparse path (only the K picked pairs computed), side by side in one process.

    python benchmarks/bench_comm_paths.py                 # random-grid and random-cross, paper sizes
    python benchmarks/bench_comm_paths.py --episodes 4 --horizon 20   # a quick look
    python benchmarks/bench_comm_paths.py --tasks random-cross --set task.group_prob=1   # every episode N = 40

One training step = a rollout of `episodes` episodes over `horizon` steps with gradients, then backward, as in
`fit` (paper budget: 50 rollouts per batch cut into 4 steps of ~13). The dense column forces the mask path for
providers that could give picks; both paths compute the same function (tests/test_policy.py).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import torch

from neurosym_cli.commands.apps import compose_config
from neurosym_cli.config import ModelConfig, TaskConfig
from neurosym_cli.dsl.parser import parse
from neurosym_cli.tasks import Rng, make_task
from neurosym_cli.policy import FullComm, NearestComm, NoComm
from neurosym_cli.policy.comm import ProgramComm
from neurosym_cli.policy.protocol import CommWrapper
from neurosym_cli.policy.transformer import CommTransformer
from neurosym_cli.rollout import rollout
from neurosym_cli.schemes import get

ROOT = Path(__file__).resolve().parent.parent
PROGRAMS = {  # the programs the paper-budget searches found on 2026-11-25 (docs/results.md), for realistic picks
    "random-grid": "argmax(map(-1.0*theta, filter(gx <= -9.04, l)))\nargmax(map(-1.0*d, filter(gd >= 2.51, l)))",
    "random-cross": "\n".join([
        "random(filter(dy >= 1.17 and gtheta >= 0.64, l))", "random(filter(gx >= 6.86 and gtheta >= -2.68, l))",
        "argmax(map(-1.0*d, filter(d >= 1.29 or theta <= -0.34, l)))",
        "random(filter(gd <= 11.01 and gtheta <= -2.78, l))", "random(filter(gd >= 3.82, l))"]),
}


class Dense(CommWrapper):
    """A provider seen through its mask only (picks withheld): forces the dense path."""

    picks_first = False

    def picks(self, ctx, r):
        return None


def task_config(name: str, overrides: list[str]) -> TaskConfig:
    return compose_config("train", [f"task={name}", *overrides]).task


def step_seconds(task: TaskConfig, comm, episodes: int, horizon: int, repeats: int) -> float:
    env = make_task(task)
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, task.rounds, ModelConfig())
    g = torch.Generator().manual_seed(0)
    rng = Rng(g, torch.device("cpu"))
    bucket = max(env.reset(episodes, g), key=lambda b: b.batch)
    best = float("inf")
    for _ in range(repeats + 1):  # the first is a warm-up
        t0 = time.perf_counter()
        traj = rollout(env, pol, comm, bucket, rng, horizon, detach_state=task.detach_state, stats=False)
        traj.cost.sum().backward()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--tasks", nargs="+", default=["random-grid", "random-cross"])
    ap.add_argument("--episodes", type=int, default=13)
    ap.add_argument("--horizon", type=int, default=0, help="0 = the task's")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--json", default="")
    ap.add_argument("--set", nargs="*", default=[], help="task overrides, e.g. task.group_prob=1 (N = 40 on cross)")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    rows = []
    print("| task | provider | dense s/step | sparse s/step | dense / sparse | vs tf-full |")
    print("|---|---|---:|---:|---:|---:|")
    for name in a.tasks:
        task = task_config(name, a.set)
        horizon = a.horizon or task.horizon
        full = step_seconds(task, FullComm(), a.episodes, horizon, a.repeats)
        rows.append({"task": name, "provider": "full", "dense_s": full})
        print(f"| {name} | tf-full | {full:.3f} | - | - | 1.00 |", flush=True)
        program = ProgramComm(parse(PROGRAMS.get(name, PROGRAMS["random-cross"])), make_task(task).features("v1"))
        expo, near = get("expo"), get("comm-range")
        for label, comm in (("no-comm", NoComm()),
                            (f"dist (K = {task.rules})", NearestComm(task.rules)),
                            ("prog", program), ("expo", expo),
                            (f"comm-range (r = {near.radius:g}, padded picks)", near)):
            dense = step_seconds(task, Dense(comm), a.episodes, horizon, a.repeats)
            sparse = step_seconds(task, comm, a.episodes, horizon, a.repeats)
            rows.append({"task": name, "provider": label, "dense_s": dense, "sparse_s": sparse})
            print(f"| {name} | {label} | {dense:.3f} | {sparse:.3f} | {dense / sparse:.2f}x | {sparse / full:.2f} |",
                  flush=True)
    if a.json:
        Path(a.json).write_text(json.dumps({"episodes": a.episodes, "threads": a.threads, "rows": rows}, indent=2))


if __name__ == "__main__":
    main()
