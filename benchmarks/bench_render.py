"""Speed of `neurosym render`: record one 200-step random-cross episode with 40 agents (the '0-1-2-3' test setting)
under a 5-rule program and under soft attention, then write its GIF and its static picture.

    python benchmarks/bench_render.py            # target: the 40-agent, 200-step animation in under 20 s

The weights are untrained (speed does not depend on them); the program is a fixed 5-rule one. Prints seconds for
the rollout record, the animation (frames per second of drawing) and the static picture, and the GIF's size.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import torch

from neurosym_cli.config import ModelConfig
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.dsl.parser import parse as parse_program
from neurosym_cli.episode import protocol_episode, record_episode
from neurosym_cli.tasks import make_task
from neurosym_cli.policy import CommTransformer, FullComm
from neurosym_cli.policy.comm import ProgramComm
from neurosym_cli.viz.animate import animate, episode_png

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
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    task = CrossConfig(name="random-cross", num_groups=4,
                       test_settings=["0", "1", "0-2", "0-1", "0-1-2", "0-1-2-3"])
    env = make_task(task, 200)
    torch.manual_seed(0)
    policy = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig())
    state, gen, _ = protocol_episode(env, 5)
    out = Path(tempfile.mkdtemp(prefix="neurosym-bench-render-"))
    for name, comm, style in (("prog", ProgramComm(parse_program(PROGRAM), "formation"), "rules"),
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


if __name__ == "__main__":
    main()
