"""A task of your own, outside the package: N agents spread from a box onto evenly spaced slots on a ring.

It shows every part of the task boundary (docs/extending.md):
- its own schema (``RingConfig``: ``radius``, ``start_half_width``, ... with docstrings and defaults);
- a state with a field the paper's tasks lack (``vel``: each agent's velocity), kept by every bucket operation;
- an agent observation of width 4 (offset to my slot, my position) and a pair observation of width 4 (the other
  agent's offset and its relative velocity): the transformer and the rl gate take both widths from the task;
- a feature map with a feature of its own (``dv``, the other agent's relative speed) beside the 2-D vectors;
- optional capabilities: ``distances`` (for dist and comm-range), ``with_team_size`` (stress), ``scene`` (render).

Run it from the repository root (the YAML is in examples/ring/conf/task/ring.yaml):

    neurosym pipeline --config-dir examples/ring/conf task=ring budget=tiny
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import torch
from torch import Tensor

from neurosym import ConfigError, Observation, Scene, TaskState, vector_map
from neurosym.tasks import (Columns, PlanarConfig, clip_speed, collision_count, column_feature, pairwise_distances,
                            relative_observation, safe_norm)


@dataclass
class RingConfig(PlanarConfig):
    """The ring: agents start in a box around the origin and each flies to its own slot on a circle. PlanarConfig
    brings what agents in the plane share (dt, v_max, noise_std, collision_dist); the ring sets its own defaults."""

    _target_: str = "ring.RingTask"
    name: str = "ring"
    agents_per_group: int = 8
    """N: agents, and slots on the ring"""
    horizon: int = 60
    rules: int = 2
    lam: float = 0.5
    radius: float = 3.0
    """world units: radius of the ring of slots"""
    start_half_width: float = 1.0
    """world units: agents start uniformly in [-w, w]^2"""
    noise_std: float = 0.02
    """world units: noise on the observed offsets"""
    collision_dist: float = 0.3
    """world units: pairs closer than this collide (a ramp of weight 2 below twice this distance)"""

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.radius <= 0:
            raise ConfigError(f"task.radius must be positive, got {self.radius}")  # one line, no traceback

    @property
    def max_agents(self) -> int:
        return self.agents_per_group


@dataclass(frozen=True)
class RingState(TaskState):
    """pos (B, N, 2) from TaskState, plus:"""

    vel: Tensor  # (B, N, 2) velocity flown in the last step, world units per second
    slot: Tensor  # (B, N, 2) each agent's slot on the ring


class RingTask:
    """Agent input s_i = [x_i - slot_i, x_i] (Ds = 4); o_ij = [x_j - x_i + noise, v_j - v_i] (Dp = 4); action = velocity."""

    Config = RingConfig
    obs_dim = 4
    pair_dim = 4
    action_dim = 2

    def __init__(self, cfg: RingConfig, horizon: int | None = None):
        self.cfg = cfg
        self.horizon = horizon or cfg.horizon
        self.rounds = cfg.rounds
        self.n = cfg.agents_per_group

    def reset(self, batch: int, gen: torch.Generator) -> list[RingState]:
        c = self.cfg
        pos = (torch.rand(batch, self.n, 2, generator=gen) * 2 - 1) * c.start_half_width
        phase = torch.rand(batch, 1, generator=gen) * 2 * math.pi  # the ring's rotation, per episode
        ang = phase + 2 * math.pi * torch.arange(self.n) / self.n  # (B, N)
        slot = c.radius * torch.stack([ang.cos(), ang.sin()], -1)
        return [RingState(pos, torch.zeros_like(pos), slot)]

    def test_episodes(self, seeder):
        gens = [seeder(k) for k in range(self.cfg.eval_episodes)]
        return [self.reset(1, g)[0] for g in gens], gens

    def observe(self, state: RingState, rng) -> Observation:
        off = relative_observation(state.pos, self.cfg.noise_std, rng)  # [i, j] = x_j - x_i + noise
        dvel = state.vel[:, None, :, :] - state.vel[:, :, None, :]
        return Observation(agent=torch.cat([state.pos - state.slot, state.pos], -1), rel=torch.cat([off, dvel], -1))

    def target(self, action: Tensor) -> Tensor:
        return clip_speed(action, self.cfg.v_max)

    def step(self, state: RingState, action: Tensor) -> RingState:
        v = clip_speed(action, self.cfg.v_max)
        return dataclasses.replace(state, pos=state.pos + self.cfg.dt * v, vel=v)

    def cost(self, next_state: RingState, action: Tensor) -> Tensor:
        """(B,) sum of distances to the slots plus a collision ramp 2 max(0, 1 - d / (2 d_c)) per pair."""
        d = safe_norm(next_state.pos[:, :, None] - next_state.pos[:, None, :])
        upper = torch.ones(self.n, self.n, dtype=torch.bool).triu(1)
        ramp = 2 * torch.relu(1 - d / (2 * self.cfg.collision_dist)) * upper
        return safe_norm(next_state.pos - next_state.slot).sum(-1) + ramp.sum((1, 2))

    def metrics(self, state: RingState) -> dict[str, Tensor]:
        return {"collisions": collision_count(state.pos, self.cfg.collision_dist)}

    def features(self, version: str):
        """my slot vector (sx sy sd stheta), my position (px ...), its offset (dx dy d theta) and dv, its speed
        relative to me."""
        dv = column_feature("dv", "other", "its speed relative to me", Columns("rel", 2), "d", "world units/s")
        return vector_map([("s", "my slot", Columns("agent", 0, -1.0)),   # slot - x: the input holds x - slot
                           ("p", "position", Columns("agent", 2))], version, extra=[dv])

    # optional capabilities
    def distances(self, state: RingState) -> Tensor:
        return pairwise_distances(state.pos)

    def with_team_size(self, n: int) -> "RingTask":
        return RingTask(dataclasses.replace(self.cfg, agents_per_group=n), self.horizon)

    def scene(self, state: RingState) -> Scene:
        return Scene(goal=state.slot[0], group=torch.zeros(state.n_agents, dtype=torch.long), labelled=True)
