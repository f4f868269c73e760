"""The bridge between a :class:`VmasState` (the truth, immutable) and VMAS's mutable ``World`` (scratch space):
write the state into the world, run VMAS's own action pipeline and physics, read the world back into a new state
(docs/vmas.md, 'The functional contract over a mutable world')."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ...utils.lazy import LazyModule
from ..base import TaskState

if TYPE_CHECKING:
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")


@dataclass(frozen=True)
class VmasState(TaskState):
    """Every physical quantity of a VMAS world, episode axis first: pos (B, N, 2) from TaskState, plus:"""

    vel: Tensor  # (B, N, 2) agent velocities, world units/s
    rot: Tensor  # (B, N, 1) agent headings, rad
    ang_vel: Tensor  # (B, N, 1) rad/s
    lm_pos: Tensor  # (B, L, 2) landmark positions (navigation: the goals; dispersion: the food)
    lm_vel: Tensor  # (B, L, 2)
    lm_rot: Tensor  # (B, L, 1)
    lm_ang_vel: Tensor  # (B, L, 1)
    reward: Tensor  # (B, N) VMAS's reward of the last step (cost=reward only; zeros otherwise)


@dataclass(frozen=True)
class World:
    """What the adapter reads once from a built scenario: landmark count, radii, action range, goal indices."""

    n_landmarks: int
    radius: tuple[float, ...]  # per agent, world units
    lm_radius: tuple[float, ...]  # per landmark
    u_range: float  # bound of each action component (force)
    goal: tuple[int, ...] | None  # landmark index of each agent's `goal`, None when agents have none
    obs_width: int  # width of scenario.observation(agent), 0 with scenario_obs off


def reset(env: Any, seed: int) -> Any:
    """Reset every episode of ``env`` through VMAS with ``seed`` (VMAS's private RNG state, not the global one)."""
    env.reset(seed=seed, return_observations=False)
    return env


def read(env: Any) -> VmasState:
    """The world's physical state as a VmasState (after a reset: no graph)."""
    w = env.world

    def stack(ents, attr, d):
        if not ents:
            return torch.zeros(env.num_envs, 0, d, device=env.device)
        return torch.stack([getattr(e.state, attr) if getattr(e.state, attr) is not None
                            else torch.zeros(env.num_envs, d, device=env.device) for e in ents], 1)

    a, lm = w.agents, w.landmarks
    return VmasState(stack(a, "pos", 2), stack(a, "vel", 2), stack(a, "rot", 1), stack(a, "ang_vel", 1),
                     stack(lm, "pos", 2), stack(lm, "vel", 2), stack(lm, "rot", 1), stack(lm, "ang_vel", 1),
                     torch.zeros(env.num_envs, len(a), device=env.device))


def write(env: Any, s: VmasState) -> None:
    """Put the state into the world. Copies: VMAS may update a state tensor in place; clone keeps the graph."""
    w = env.world
    for ents, fields in ((w.agents, (s.pos, s.vel, s.rot, s.ang_vel)),
                         (w.landmarks, (s.lm_pos, s.lm_vel, s.lm_rot, s.lm_ang_vel))):
        for k, e in enumerate(ents):
            for attr, t in zip(("vel", "pos", "rot", "ang_vel"), (fields[1], fields[0], fields[2], fields[3])):
                if getattr(e.state, attr) is not None:
                    setattr(e.state, attr, t[:, k].clone())


def physics(env: Any, s: VmasState, force: Tensor) -> VmasState:
    """One VMAS step from state s with actions (B, N, 2) inside the bounds: VMAS's Environment.step without its
    observations, rewards and dones."""
    write(env, s)
    for k, agent in enumerate(env.world.agents):
        env._set_action(force[:, k], agent)
    for agent in env.world.agents:
        env.scenario.env_process_action(agent)
    env.scenario.pre_step()
    env.world.step()
    env.scenario.post_step()
    return read(env)


def observations(env: Any, s: VmasState) -> Tensor:
    """(B, N, Do) the scenario's own observation of every agent in state s (its lidar reads the world)."""
    write(env, s)
    return torch.stack([env.scenario.observation(a) for a in env.world.agents], 1).to(s.pos.dtype)


def rewards(env: Any) -> Tensor:
    """(B, N) the scenario's reward of every agent in the world as it is."""
    return torch.stack([env.scenario.reward(a) for a in env.world.agents], -1)
