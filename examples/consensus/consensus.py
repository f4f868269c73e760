"""A task where communication matters: N agents must meet at one common goal that each of them knows only roughly.

Every agent holds its own estimate of the goal, off by a fixed error drawn once per episode (std ``estimate_std``
per axis, as wide as the arena). Alone, an agent can do no better than fly to its own estimate; hearing others
lets it average their estimates (the message of j carries j's state s_j), and the error of an average of m
independent estimates is estimate_std / sqrt(m). So tf-full (everybody hears everybody) beats no-comm by a wide
margin, and a program that hears two others (m = 3) already closes most of that gap at a small degree.

The parts of the task boundary it shows (docs/extending.md), like examples/ring:
- its own schema (``ConsensusConfig``: ``estimate_std``, ``goal_half_width``, ``start_half_width``);
- a state with fields of its own (``vel``, ``goal``, ``estimate``), kept by every bucket operation;
- an agent observation of width 4 (my estimate of the goal relative to me, my velocity) and a pair observation of
  width 4 (the other agent's offset and relative velocity);
- a cost averaged over agents (``cost_words``), so the loss reads as the mean distance to the goal in world units;
- a feature map of exportable 2-D vectors (``Columns``) with a feature of its own (``dv``).

Run it from the repository root (the YAML is in examples/consensus/conf/task/consensus.yaml):

    neurosym pipeline --config-dir examples/consensus/conf task=consensus budget=tiny
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import torch
from torch import Tensor

from neurosym import ConfigError, Observation, Scene, TaskState, vector_map
from neurosym.tasks import (Columns, PlanarConfig, clip_speed, column_feature, pairwise_distances,
                            relative_observation, safe_norm)


@dataclass
class ConsensusConfig(PlanarConfig):
    """Consensus: a goal drawn in a box, agents drawn in a wider box, each agent with its own noisy estimate of the
    goal. PlanarConfig brings dt, v_max, noise_std (on the observed offsets) and collision_dist (unused here)."""

    _target_: str = "consensus.ConsensusTask"
    name: str = "consensus"
    agents_per_group: int = 12
    """N: agents, all heading for the one goal"""
    horizon: int = 30
    rules: int = 2
    estimate_std: float = 1.5
    """world units: std per axis of each agent's fixed error on the goal (drawn once per episode and agent)"""
    goal_half_width: float = 2.0
    """world units: the goal is drawn uniformly in [-w, w]^2"""
    start_half_width: float = 6.0
    """world units: agents start uniformly in [-w, w]^2"""
    reach_dist: float = 0.5
    """world units: an agent this close to the goal counts as arrived (the ``arrived`` metric)"""

    def __post_init__(self) -> None:
        super().__post_init__()
        for key in ("estimate_std", "goal_half_width", "start_half_width", "reach_dist"):
            if getattr(self, key) < 0:
                raise ConfigError(f"task.{key} must be non-negative, got {getattr(self, key)}")  # one line


@dataclass(frozen=True)
class ConsensusState(TaskState):
    """pos (B, N, 2) from TaskState, plus:"""

    vel: Tensor  # (B, N, 2) velocity flown in the last step, world units per second
    goal: Tensor  # (B, 1, 2) the true goal, the same for every agent
    estimate: Tensor  # (B, N, 2) each agent's estimate of the goal (goal + its fixed error), world coordinates


class ConsensusTask:
    """Agent input s_i = [g^_i - x_i, v_i] (Ds = 4); o_ij = [x_j - x_i + noise, v_j - v_i] (Dp = 4); action =
    velocity. Cost per step: the mean over agents of |x_i - g|."""

    Config = ConsensusConfig
    obs_dim = 4
    pair_dim = 4
    action_dim = 2
    cost_words = "averaged over agents"

    def __init__(self, cfg: ConsensusConfig, horizon: int | None = None):
        self.cfg = cfg
        self.horizon = horizon or cfg.horizon
        self.rounds = cfg.rounds
        self.n = cfg.agents_per_group

    def reset(self, batch: int, gen: torch.Generator) -> list[ConsensusState]:
        c = self.cfg
        pos = (torch.rand(batch, self.n, 2, generator=gen) * 2 - 1) * c.start_half_width
        goal = (torch.rand(batch, 1, 2, generator=gen) * 2 - 1) * c.goal_half_width
        estimate = goal + c.estimate_std * torch.randn(batch, self.n, 2, generator=gen)
        return [ConsensusState(pos, torch.zeros_like(pos), goal, estimate)]

    def test_episodes(self, seeder):
        gens = [seeder(k) for k in range(self.cfg.eval_episodes)]
        return [self.reset(1, g)[0] for g in gens], gens

    def observe(self, state: ConsensusState, rng) -> Observation:
        off = relative_observation(state.pos, self.cfg.noise_std, rng)  # [i, j] = x_j - x_i + noise
        dvel = state.vel[:, None, :, :] - state.vel[:, :, None, :]  # [i, j] = v_j - v_i
        return Observation(agent=torch.cat([state.estimate - state.pos, state.vel], -1),
                           rel=torch.cat([off, dvel], -1))

    def target(self, action: Tensor) -> Tensor:
        return clip_speed(action, self.cfg.v_max)

    def step(self, state: ConsensusState, action: Tensor) -> ConsensusState:
        v = clip_speed(action, self.cfg.v_max)
        return dataclasses.replace(state, pos=state.pos + self.cfg.dt * v, vel=v)

    def cost(self, next_state: ConsensusState, action: Tensor) -> Tensor:
        """(B,) the mean over agents of the distance to the true goal, world units."""
        return safe_norm(next_state.pos - next_state.goal).mean(-1)

    def metrics(self, state: ConsensusState) -> dict[str, Tensor]:
        """(B,) arrived: the share of agents within reach_dist of the goal."""
        near = (state.pos - state.goal).norm(dim=-1) < self.cfg.reach_dist
        return {"arrived": near.to(state.pos.dtype).mean(-1)}

    def features(self, version: str):
        """my estimate of the goal (gx gy gd gtheta), my velocity (vx ...), its offset (dx dy d theta) and dv, its
        speed relative to me."""
        dv = column_feature("dv", "other", "its speed relative to me", Columns("rel", 2), "d", "world units/s")
        return vector_map([("g", "my estimate of the goal", Columns("agent", 0)),
                           ("v", "velocity", Columns("agent", 2))], version, extra=[dv])

    # optional capabilities
    def distances(self, state: ConsensusState) -> Tensor:
        return pairwise_distances(state.pos)

    def with_team_size(self, n: int) -> "ConsensusTask":
        return ConsensusTask(dataclasses.replace(self.cfg, agents_per_group=n), self.horizon)

    def scene(self, state: ConsensusState) -> Scene:
        return Scene(goal=state.goal[0], group=torch.zeros(state.n_agents, dtype=torch.long), labelled=False)
