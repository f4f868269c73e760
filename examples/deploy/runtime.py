"""One episode with every agent deciding on its own, from a `neurosym export` folder and its own observations only.

    python examples/deploy/runtime.py FOLDER [--episode K] [--tolerance 1e-4] [world overrides ...]
    python examples/deploy/runtime.py outputs/random-cross/tiny/seed0/export/prog-retrained-k5-lam0.5-v1 \\
        task=random-cross budget=tiny

The agents (one process, agents as a loop) use nothing but the folder: program.py decides whom each asks,
agent/*.onnx what the asked agents answer and what each does with the answers (agent_runtime.py). neurosym
appears only as the *world*: it places the agents (episode K of the evaluation protocol), gives each agent its
own noisy observations, draws the uniforms each agent's random rules consume (row i of the draw for agent i, as
neurosym does, so the run replays `neurosym eval`'s episode exactly), applies the actions and scores them. The
world overrides are those of the run that made the export (task=, budget=, --config-dir DIR for a task of one's
own). Prints the episode's loss beside the one the evaluation's rollout recorded (golden.json); exit 1 when they
differ by more than the relative tolerance.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def world(overrides: list[str], config_dir: str | None):
    """The task as neurosym builds it for these overrides (the simulator the agents live in)."""
    import neurosym as ns

    cfg = ns.compose("export", overrides, config_dir=config_dir)
    return ns.task(cfg)


def run_episode(folder: Path, task, episode: int):
    """(loss, per-step costs) of episode ``episode`` with every agent run from the export folder."""
    import torch

    from neurosym_cli.episode import protocol_episode
    from neurosym_cli.tasks import Rng

    sys.path.insert(0, str(folder))
    from agent_runtime import Agent, Export, team_step  # the exported runtime: numpy and onnxruntime only

    team = Export(folder)
    if team.program is None:
        raise SystemExit("this export has no program: whom each agent hears must come from elsewhere")
    state, gen, _ = protocol_episode(task, episode)
    rng = Rng([gen], "cpu")
    agents = [Agent(team, i) for i in range(state.n_agents)]
    costs = []
    with torch.no_grad():
        for _ in range(task.horizon):
            obs = task.observe(state, rng)  # each agent's own noisy observations (row i is agent i's)
            n = state.n_agents
            # what each agent's own generator would draw: per round, per random rule, n uniforms for agent i
            draws = [[rng.rand(1, n, n)[0].numpy() for _ in range(team.program.RANDOM_RULES[r])]
                     for r in range(team.rounds)]

            def uniforms(r, i):
                return iter([float(u) for d in draws[r] for u in d[i]]).__next__

            team_step(team, agents, obs.agent[0].numpy(), obs.rel[0].numpy(), uniforms=uniforms)
            raw = torch.from_numpy(np.stack([a.raw for a in agents]))[None]  # Task.step takes the raw action
            state = task.step(state, raw)
            costs.append(float(task.cost(state, raw)[0]))
    return float(np.mean(costs)), costs


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("--episode", type=int, default=0, help="the evaluation protocol's episode (one of golden.json's)")
    ap.add_argument("--tolerance", type=float, default=1e-4, help="relative tolerance on the episode loss")
    ap.add_argument("--config-dir", default=None, help="config directory of a task of one's own")
    args, overrides = ap.parse_known_args()
    folder = Path(args.folder).resolve()
    golden = {e["episode"]: e for e in json.loads((folder / "golden.json").read_text())["episodes"]}
    task = world(overrides, args.config_dir)
    loss, _ = run_episode(folder, task, args.episode)
    ref = golden.get(args.episode, {}).get("loss")
    if ref is None:
        print(f"episode {args.episode}: loss {loss:.6f} (no recorded loss for this episode to compare with)")
        return 0
    rel = abs(loss - ref) / max(abs(ref), 1e-12)
    ok = rel <= args.tolerance
    print(f"episode {args.episode}: decentralised loss {loss:.6f}, neurosym eval's rollout {ref:.6f} "
          f"(relative difference {rel:.2g}, tolerance {args.tolerance:g}): {'match' if ok else 'MISMATCH'}")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
