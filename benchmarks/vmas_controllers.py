"""What hearing the others can buy on VMAS navigation, before any training (docs/vmas.md, "Where communication
matters"): hand-written controllers step a VmasTask directly, one blind to the others (a PD controller to the own
goal) and one that also steers away from the agents within R (what hearing them allows); gains and R are swept and
the best of each is printed per collision weight w, as the cost per step (summed over agents, averaged over T).

    python benchmarks/vmas_controllers.py                       # the scenes of docs/vmas.md, about a minute
    python benchmarks/vmas_controllers.py --scenes base --episodes 32
"""

from __future__ import annotations

import argparse
import itertools

import torch

from neurosym_cli.tasks.base import safe_norm
from neurosym_cli.tasks.vmas.task import VmasConfig, VmasTask

SCENES = {  # name -> (team size, make_world keywords)
    "base": (6, {}),
    "no-contact": (6, {"collisions": False}),
    "N10": (10, {}),
    "radius0.15": (6, {"agent_radius": 0.15}),
    "box0.6": (6, {"world_spawning_x": 0.6, "world_spawning_y": 0.6}),
}
WEIGHTS = (1.0, 3.0, 5.0, 10.0)


def blind(s, goal, kp: float, kd: float):
    """(B, N, 2) force: PD to the own goal, nothing of the others."""
    return kp * (goal - s.pos) - kd * s.vel


def informed(s, goal, radius: float, gain: float):
    """(B, N, 2) force: PD to the goal plus a push away from every agent within ``radius`` (world units)."""
    off = s.pos[:, :, None] - s.pos[:, None, :]  # [i, j] = x_i - x_j
    d = safe_norm(off)
    w = torch.relu(1 - d / radius) * (1 - torch.eye(s.pos.shape[1]))
    return blind(s, goal, 2.0, 1.0) + gain * (w[..., None] * off / d[..., None].clamp_min(1e-3)).sum(2)


def rollout(task: VmasTask, act, episodes: int, seed: int) -> tuple[float, float]:
    """Per step, averaged over the episodes and T: (goal distance summed over agents, collision ramp of weight 1)."""
    (s,) = task.reset(episodes, torch.Generator().manual_seed(seed))
    goal_d = ramp = 0.0
    with torch.no_grad():
        for _ in range(task.horizon):
            s = task.step(s, act(s, task.goal_pos(s)))
            d = float(safe_norm(s.pos - task.goal_pos(s)).sum(-1).mean())
            goal_d, ramp = goal_d + d, ramp + float(task.cost(s, torch.zeros_like(s.pos)).mean()) - d  # w = 1
    return goal_d / task.horizon, ramp / task.horizon


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    ap.add_argument("--episodes", type=int, default=16)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    torch.set_num_threads(1)
    for name in a.scenes:
        n, kw = SCENES[name]
        task = VmasTask(VmasConfig(name="probe", scenario="navigation", scenario_kwargs=kw, team_sizes=[n],
                                   horizon=60, scenario_obs=False, collision_weight=1.0))
        run = lambda act: rollout(task, act, a.episodes, a.seed)  # noqa: E731
        blinds = {f"kp {kp} kd {kd}": run(lambda s, g, kp=kp, kd=kd: blind(s, g, kp, kd))
                  for kp, kd in itertools.product((1, 2, 4), (0.5, 1, 2))}
        heard = {f"R {r} gain {k}": run(lambda s, g, r=r, k=k: informed(s, g, r, k))
                 for r, k in itertools.product((0.3, 0.45, 0.6, 0.8), (1, 2, 4, 8))}
        print(f"{name} (N = {n}, {kw or 'VMAS defaults'}):")
        for w in WEIGHTS:
            (bn, (bg, br)), (hn, (hg, hr)) = (min(c.items(), key=lambda x: x[1][0] + w * x[1][1])
                                              for c in (blinds, heard))
            b, h = bg + w * br, hg + w * hr
            print(f"  w {w:g}: blind {b:.2f} ({bn}), hearing {h:.2f} ({hn}): hearing gains {(b - h) / b:+.0%}")


if __name__ == "__main__":
    main()
