"""Speed of `neurosym render`: record one 200-step random-cross episode with 40 agents (the '0-1-2-3' test setting)
under a 5-rule program and under soft attention, then write its GIF and its static picture.

    python benchmarks/bench_render.py            # target: the 40-agent, 200-step animation in under 20 s
    python benchmarks/bench_render.py --swarm 1000,10000 --steps 200,20   # swarm episodes: record, memory, frames

The weights are untrained (speed does not depend on them); the program is a fixed 5-rule one. Prints seconds for
the rollout record, the animation (frames per second of drawing) and the static picture, and the GIF's size.
``--swarm``: the same for swarm episodes of those sizes under the program (the sparse path), with the recorded
episode's bytes against the (T, R, N, N) masks and weights an episode kept before it recorded edges, the process's
peak memory, and the crowd animation (every 10th step).
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

from neurosym_cli.config import ModelConfig  # before torch: the CPU kernels are pinned (cpu_kernels)
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.dsl.parser import parse as parse_program
from neurosym_cli.episode import protocol_episode, record_episode
from neurosym_cli.tasks import make_task
from neurosym_cli.policy import CommTransformer, FullComm
from neurosym_cli.policy.comm import ProgramComm
from neurosym_cli.viz.animate import animate, episode_png

import torch  # noqa: E402

PROGRAM = """argmax(map(-1.0*d, filter(theta >= -1.85, l)))
random(filter(d >= 3.41, l))
argmax(map(gd, filter(d <= 2.0, l)))
random(filter(dx <= -1.0, l))
argmax(map(-1.0*theta, filter(dy <= 0.46, l)))
"""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--every", type=int, default=1)
    ap.add_argument("--swarm", default="", help="comma-separated swarm sizes N to record and draw (e.g. 1000,10000)")
    ap.add_argument("--steps", default="200", help="steps of each swarm episode (one value, or one per size)")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    if args.swarm:
        sizes = [int(x) for x in args.swarm.split(",")]
        steps = [int(x) for x in args.steps.split(",")]
        for n, t in zip(sizes, steps if len(steps) == len(sizes) else steps * len(sizes)):
            swarm(n, t, args.every)
        return
    task = CrossConfig(name="random-cross", num_groups=4,
                       test_settings=["0", "1", "0-2", "0-1", "0-1-2", "0-1-2-3"])
    env = make_task(task, 200)
    torch.manual_seed(0)
    policy = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig())
    state, gen, _ = protocol_episode(env, 5)
    out = Path(tempfile.mkdtemp(prefix="neurosym-bench-render-"))
    for name, comm, style in (("prog", ProgramComm(parse_program(PROGRAM), env.features("v1")), "rules"),
                              ("tf-full", FullComm(), "weights")):
        g = torch.Generator().manual_seed(int(gen.initial_seed()))
        t0 = time.perf_counter()
        rec = record_episode(env, policy, comm, state, g, torch.device("cpu"))
        t1 = time.perf_counter()
        gif, frames = animate(rec, out / f"{name}.gif", f"benchmark: {name}", style, every=args.every)
        t2 = time.perf_counter()
        episode_png(rec, out / f"{name}.png", f"benchmark: {name}")
        t3 = time.perf_counter()
        print(f"{name:8s} N={rec.n_agents} T={rec.steps}: record {t1 - t0:5.2f} s | animation {t2 - t1:5.2f} s "
              f"({frames} frames, {frames / (t2 - t1):.0f} frames/s, {gif.stat().st_size / 1e6:.1f} MB) | "
              f"picture {t3 - t2:4.2f} s | all {t3 - t0:5.2f} s")
    print(f"files in {out}")


def _bytes(rec) -> int:
    """Bytes of a recorded episode's arrays."""
    arrays = [rec.pos, rec.inputs, rec.goal, rec.group, rec.cost, rec.collide, rec.edges.start, rec.edges.recv,
              rec.edges.sent, rec.edges.weight] + [a for a in (rec.picks, rec.edges.rule) if a is not None]
    return sum(a.nbytes for a in arrays)


def swarm(n: int, steps: int, every: int) -> None:
    """Record one swarm episode of N agents under the program and draw its crowd animation (every 10th step)."""
    from neurosym_cli.tasks.swarm import SwarmConfig

    env = make_task(SwarmConfig(name="swarm", agents_per_group=n // 2), steps)
    torch.manual_seed(0)
    policy = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig())
    state, gen, _ = protocol_episode(env, 0)
    out = Path(tempfile.mkdtemp(prefix="neurosym-bench-render-swarm-"))
    peak0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    t0 = time.perf_counter()
    rec = record_episode(env, policy, ProgramComm(parse_program(PROGRAM), env.features("v1")), state, gen,
                         torch.device("cpu"))
    t1 = time.perf_counter()
    gif, frames = animate(rec, out / "swarm.gif", f"benchmark: swarm N = {n}", "rules", every=max(every, 10))
    t2 = time.perf_counter()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    dense = steps * rec.rounds * n * n * 5  # a bool mask and a float32 weight per pair, step and round
    print(f"swarm N={n} T={steps}: record {t1 - t0:6.1f} s ({(t1 - t0) / steps:.3f} s a step), episode "
          f"{_bytes(rec) / 1e6:.1f} MB ({rec.edges.recv.size:,} edges; dense masks and weights: "
          f"{dense / 1e9:.1f} GB) | "
          f"animation {t2 - t1:5.1f} s ({frames} frames, {gif.stat().st_size / 1e6:.1f} MB) | "
          f"peak RSS {peak:.2f} GB (before the episode {peak0:.2f} GB)")


if __name__ == "__main__":
    main()
