"""Retraining a swarm under a program (issue 39's 2x at N = 1,000): the sparse path as it was (every pair of the
program's filter scan computed by policy/scan_kernels.py, the cell list's ranges by torch.searchsorted, the noise
of the picked pairs by torch ops) against now (the scan decided by cells, policy/scan_cells.py; the ranges' table
and the noise by compiled loops, tasks/pair_kernels.py cell_ranges and noise_at), their optimizer steps
alternated in one process so that both see the same load.

    python benchmarks/bench_swarm_retrain.py                         # N = 1,000, B = 2, T = 200, 6 steps each
    python benchmarks/bench_swarm_retrain.py --agents 300 --horizon 50 --steps 4       # a quick look
    python benchmarks/bench_swarm_retrain.py --paths before,now,ramps-torch    # also now without the ramps' kernels

One optimizer step = one BPTT rollout of B episodes of T steps under the program (the swarm's reset, the
transformer over the picks, the collision cost by the cell list), backward, Adam, as retraining runs it. Both paths
start from the same weights and generators; their picks and pairs are the same, so their losses must be equal bit
for bit (checked). Timing: CPU seconds of this process per 200-step rollout of one episode (median over the
steps after the first; the first loads the compiled kernels), with wall seconds beside them; one torch thread.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import neurosym_cli  # noqa: F401  (pins the CPU kernels before torch loads)
import torch

from neurosym_cli.config import ModelConfig
from neurosym_cli.dsl.parser import parse
from neurosym_cli.policy import scan
from neurosym_cli.policy.comm import ProgramComm
from neurosym_cli.policy.transformer import CommTransformer
from neurosym_cli.rollout import rollout
from neurosym_cli.tasks import pairs
from neurosym_cli.tasks.base import Rng
from neurosym_cli.tasks.swarm import SwarmConfig, SwarmTask

PROGRAM = "argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nrandom(filter(d >= 3.6, l))"
"""the program of docs/performance.md section 15 (the nearest agent ahead, a random one at least 3.6 away)"""
PATHS = {"before": (10 ** 9, False, False), "now": (0, True, True), "ramps-torch": (0, True, False)}
"""path -> (scan.CELLS_FROM, pairs.COMPILED_LOOPS, pairs.COMPILED_RAMPS); 'ramps-torch' is now with the collision
ramps as torch ops (what their kernels buy)"""


def _steps(env, path: str, *, batch: int, horizon: int, program: str):
    """Optimizer steps on one path, one per ``next``: yields (loss, wall s, CPU s)."""
    torch.manual_seed(0)
    policy = CommTransformer.for_task(env, ModelConfig())
    comm = ProgramComm(parse(program), env.features("v1"))
    opt = torch.optim.Adam(policy.parameters(), 1e-3)
    gen = torch.Generator().manual_seed(1)
    rng = Rng(gen)
    mine = torch.random.get_rng_state()
    while True:
        torch.random.set_rng_state(mine)  # dropout's stream, as if this path ran alone
        scan.CELLS_FROM, pairs.COMPILED_LOOPS, pairs.COMPILED_RAMPS = PATHS[path]
        t0, c0 = time.perf_counter(), time.process_time()
        state = env.reset(batch, gen)[0]
        traj = rollout(env, policy, comm, state, rng, horizon, stats=False)
        loss = traj.cost.sum() / (batch * horizon)
        loss.backward()
        opt.step()
        opt.zero_grad(set_to_none=True)
        mine = torch.random.get_rng_state()
        yield float(loss.detach()), time.perf_counter() - t0, time.process_time() - c0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--agents", type=int, default=1000, help="N (two groups of N / 2)")
    ap.add_argument("--batch", type=int, default=2)
    ap.add_argument("--horizon", type=int, default=200)
    ap.add_argument("--steps", type=int, default=6, help="optimizer steps per path")
    ap.add_argument("--paths", default="before,now", help="the paths to run (one alone: to run 'before' on an older "
                    "checkout, PYTHONPATH=<its root>, where the switches do not exist and its own code runs)")
    ap.add_argument("--json", default="", help="also write the result here")
    args = ap.parse_args()
    torch.set_num_threads(1)
    env = SwarmTask(SwarmConfig(name="swarm", agents_per_group=args.agents // 2))
    paths = args.paths.split(",")
    its = {p: _steps(env, p, batch=args.batch, horizon=args.horizon, program=PROGRAM) for p in paths}
    done: dict[str, list] = {p: [] for p in paths}
    for s in range(args.steps):
        for p in paths:
            done[p].append(next(its[p]))
        print(f"step {s + 1}/{args.steps}: " + ", ".join(
            f"{p} loss {done[p][-1][0]:.6g}, {done[p][-1][2]:.1f} CPU s" for p in paths), flush=True)
    scale = 200 / (args.horizon * args.batch)  # per 200-step rollout of one episode
    row = {"agents": args.agents, "batch": args.batch, "horizon": args.horizon, "steps": args.steps,
           "program": PROGRAM, "code": neurosym_cli.__file__}
    for p in paths:
        rest = done[p][1:] or done[p]
        row[p] = {"cpu_s_per_rollout": statistics.median(r[2] for r in rest) * scale,
                  "wall_s_per_rollout": statistics.median(r[1] for r in rest) * scale,
                  "losses": [r[0] for r in done[p]]}
    if len(paths) == 1:
        print(f"{paths[0]}: {row[paths[0]]['cpu_s_per_rollout']:.2f} CPU s a rollout, losses {row[paths[0]]['losses']}")
        if args.json:
            with open(args.json, "w") as f:
                json.dump(row, f, indent=1)
        return
    row["losses_equal"] = all(row[p]["losses"] == row["now"]["losses"] for p in paths)
    if "ramps-torch" in paths:
        row["ratio_cpu_ramps"] = row["ramps-torch"]["cpu_s_per_rollout"] / row["now"]["cpu_s_per_rollout"]
        print(f"the ramps' kernels: {row['ramps-torch']['cpu_s_per_rollout']:.2f} -> "
              f"{row['now']['cpu_s_per_rollout']:.2f} CPU s a rollout ({row['ratio_cpu_ramps']:.2f}x)")
    row["ratio_cpu"] = row["before"]["cpu_s_per_rollout"] / row["now"]["cpu_s_per_rollout"]
    row["ratio_wall"] = row["before"]["wall_s_per_rollout"] / row["now"]["wall_s_per_rollout"]
    print(f"N = {args.agents:,}, B = {args.batch}, T = {args.horizon}: before "
          f"{row['before']['cpu_s_per_rollout']:.2f} CPU s a rollout, now {row['now']['cpu_s_per_rollout']:.2f}: "
          f"{row['ratio_cpu']:.2f}x (wall {row['ratio_wall']:.2f}x); losses equal: {row['losses_equal']}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(row, f, indent=1)


if __name__ == "__main__":
    main()
