"""Unlabeled goals (paper section 4): N agents must cover N goals with no assignment given.

Each agent outputs weights p_i over the goals (in its own order: goals sorted by initial distance) and moves
along sum_k p_ik (g_k - x_i), speed clipped to v_max (paper; ``velocity=reference`` uses the reference's
v_max * sum_k p_ik unit(g_k - x_i)). The loss of a step is N - sum_k max_i p_ik: the number of uncovered goals
on the paper's plot scale (docs/fidelity.md).
"""

from __future__ import annotations

import torch
from torch import Tensor

from ..config import UnlabeledConfig
from ..utils.ops import softmax_last
from .base import EnvState, EpisodeSeeder, Observation, Rng, clip_speed, eye_mask, safe_norm
from .sampling import sample_in_boxes


class UnlabeledGoalsEnv:
    """Agent input s_i = [x_i, x_i - g_sigma_i(1), ..., x_i - g_sigma_i(G)] (obs_dim 2 + 2G); action = G logits."""

    def __init__(self, cfg: UnlabeledConfig, horizon: int | None = None):
        self.cfg = cfg
        self.horizon = horizon or cfg.horizon
        self.n = cfg.agents_per_group
        self.obs_dim = 2 + 2 * self.n
        self.action_dim = self.n

    def reset(self, batch: int, gen: torch.Generator) -> list[EnvState]:
        c = self.cfg
        zeros = torch.zeros(batch, 2)
        pos = sample_in_boxes(zeros, self.n, c.start_half_width, c.start_separation, gen)  # (B, N, 2)
        goal = sample_in_boxes(zeros, self.n, c.goal_half_width, c.goal_separation, gen)  # (B, G, 2)
        # each agent orders the goals by their distance at t = 0; the order is fixed for the episode
        order = torch.cdist(pos, goal).argsort(-1)  # (B, N, G)
        group = torch.zeros(batch, self.n, dtype=torch.long)
        return [EnvState(pos, goal, group, order)]

    def test_episodes(self, seeder: EpisodeSeeder) -> tuple[list[EnvState], list[torch.Generator]]:
        """``eval_episodes`` random episodes of one evaluation seed, each with its own generator."""
        gens = [seeder(k) for k in range(self.cfg.eval_episodes)]
        return [self.reset(1, g)[0] for g in gens], gens

    def observe(self, state: EnvState, rng: Rng) -> Observation:
        b, n = state.batch, state.n_agents
        assert state.goal_order is not None
        sorted_goals = torch.gather(state.goal[:, None].expand(-1, n, -1, -1), 2,
                                    state.goal_order[..., None].expand(-1, -1, -1, 2))  # (B, N, G, 2)
        offsets = (state.pos[:, :, None, :] - sorted_goals).flatten(2)  # (B, N, 2G)
        rel = state.pos[:, None, :, :] - state.pos[:, :, None, :]  # (B, N, N, 2): x_j - x_i
        if self.cfg.noise_std > 0:
            rel = rel + self.cfg.noise_std * rng.randn(b, n, n, 2)
        return Observation(agent=torch.cat([state.pos, offsets], -1), rel=rel)

    def goal_weights(self, state: EnvState, action: Tensor) -> Tensor:
        """(B, N, G) softmax weights indexed by absolute goal id (the action is in each agent's own order)."""
        assert state.goal_order is not None
        p = softmax_last(action)
        return torch.zeros_like(p).scatter(-1, state.goal_order, p)

    def effective_action(self, action: Tensor) -> Tensor:
        """(B, N, G) the goal weights p_i: what synthesis imitates."""
        return softmax_last(action)

    def step(self, state: EnvState, action: Tensor) -> EnvState:
        p = self.goal_weights(state, action)  # (B, N, G)
        to_goal = state.goal[:, None, :, :] - state.pos[:, :, None, :]  # (B, N, G, 2)
        if self.cfg.velocity == "reference":
            v = self.cfg.v_max * (p[..., None] * to_goal / safe_norm(to_goal)[..., None]).sum(2)
        else:
            v = (p[..., None] * to_goal).sum(2)
        v = clip_speed(v, self.cfg.v_max)
        return EnvState(state.pos + self.cfg.dt * v, state.goal, state.group, state.goal_order)

    def cost(self, next_state: EnvState, action: Tensor) -> Tensor:
        """(B,) uncovered goals: N - sum_k max_i p_ik."""
        p = self.goal_weights(next_state, action)
        return self.n - p.amax(1).sum(-1)

    def collisions(self, state: EnvState) -> Tensor:
        d = torch.cdist(state.pos, state.pos)
        upper = torch.ones_like(d[0], dtype=torch.bool).triu(1)
        return ((d < self.cfg.collision_dist) & upper).sum((1, 2)).to(d.dtype)

    def true_distance(self, state: EnvState) -> Tensor:
        d = torch.cdist(state.pos, state.pos)
        return d.masked_fill(eye_mask(state.n_agents, d.device), float("inf"))
