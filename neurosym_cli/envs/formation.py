"""Formation flying (paper section 4): agents in groups fly from start boxes to goal boxes without colliding.

The dynamics, observation and cost shared by the formation tasks; each task's file says where its groups start
and where they go: random_cross.py, two_groups_cross.py, random_grid.py. Constants: docs/fidelity.md; every
one is a field of :class:`~neurosym_cli.config.FormationConfig`.
"""

from __future__ import annotations

import torch
from torch import Tensor

from ..config import FormationConfig
from .base import EnvState, EpisodeSeeder, Observation, Rng, clip_speed, eye_mask, safe_norm
from .sampling import sample_in_boxes


class FormationEnv:
    """Batched formation flying. Agent input s_i = x_i - g_i (obs_dim 2); action = velocity (A = 2).

    A task subclass samples episodes (``reset``) and builds its fixed test settings (``setting``)."""

    obs_dim = 2
    action_dim = 2

    def __init__(self, cfg: FormationConfig, horizon: int | None = None):
        self.cfg = cfg
        self.horizon = horizon or cfg.horizon
        self.n = cfg.agents_per_group

    def reset(self, batch: int, gen: torch.Generator) -> list[EnvState]:
        """Sample ``batch`` random episodes, returned as buckets of equal agent count."""
        raise NotImplementedError

    def setting(self, name: str, gen: torch.Generator) -> EnvState:
        """One episode of a named fixed test setting."""
        raise NotImplementedError

    def _bucket(self, start_c: Tensor, goal_c: Tensor, gen: torch.Generator) -> EnvState:
        """start_c, goal_c: (E, g, 2) box centres of the g groups of E episodes -> EnvState with N = g n."""
        e, g, _ = start_c.shape
        c = self.cfg
        starts = sample_in_boxes(start_c.reshape(-1, 2), self.n, c.box_half_width, c.min_separation, gen)
        goals = sample_in_boxes(goal_c.reshape(-1, 2), self.n, c.box_half_width, c.min_separation, gen)
        group = torch.arange(g).repeat_interleave(self.n).expand(e, -1)  # (E, N)
        return EnvState(starts.reshape(e, g * self.n, 2), goals.reshape(e, g * self.n, 2), group.clone())

    def test_episodes(self, seeder: EpisodeSeeder) -> tuple[list[EnvState], list[torch.Generator]]:
        """The single-episode states of one evaluation seed: each test setting once (reference protocol), or
        ``eval_episodes`` random episodes. ``seeder(k)`` gives episode k its own generator, used for its initial
        state and later for its noise."""
        names = self.cfg.test_settings
        gens = [seeder(k) for k in range(len(names) if names else self.cfg.eval_episodes)]
        if names:
            return [self.setting(nm, g) for nm, g in zip(names, gens)], gens
        return [self.reset(1, g)[0] for g in gens], gens

    # ---------------------------------------------------------------------------------------- dynamics
    def observe(self, state: EnvState, rng: Rng) -> Observation:
        b, n = state.batch, state.n_agents
        rel = state.pos[:, None, :, :] - state.pos[:, :, None, :]  # (B, N, N, 2): [i, j] = x_j - x_i
        if self.cfg.noise_std > 0:
            rel = rel + self.cfg.noise_std * rng.randn(b, n, n, 2)
        return Observation(agent=state.pos - state.goal, rel=rel)

    def effective_action(self, action: Tensor) -> Tensor:
        """(B, N, 2) the velocity actually flown (speed-clipped): what synthesis imitates."""
        return clip_speed(action, self.cfg.v_max)

    def step(self, state: EnvState, action: Tensor) -> EnvState:
        """action: (B, N, 2) desired velocity; the speed is clipped to v_max, x <- x + dt v."""
        v = clip_speed(action, self.cfg.v_max)
        return EnvState(state.pos + self.cfg.dt * v, state.goal, state.group)

    def cost(self, next_state: EnvState, action: Tensor) -> Tensor:
        """(B,) loss of one step: sum_i ||x_i - g_i|| plus the collision ramps (paper section 4)."""
        dist = safe_norm(next_state.pos - next_state.goal).sum(-1)
        return dist + self.collision_cost(next_state)

    def _pair_geometry(self, state: EnvState) -> tuple[Tensor, Tensor, Tensor]:
        n = state.n_agents
        d = safe_norm(state.pos[:, :, None, :] - state.pos[:, None, :, :])  # (B, N, N)
        same = state.group[:, :, None] == state.group[:, None, :]  # (B, N, N)
        upper = torch.ones(n, n, dtype=torch.bool, device=d.device).triu(1)  # unordered pairs i < j
        return d, same, upper

    def collision_cost(self, state: EnvState) -> Tensor:
        """(B,) ramp max(0, p (2 - d_ij / d)) over unordered pairs; across groups with the inter-group p, d."""
        c = self.cfg
        d, same, upper = self._pair_geometry(state)
        p_across = c.collision_inter_group_weight
        weight = torch.where(same, c.collision_weight, p_across) * upper  # (B, N, N): p of each pair, 0 off i < j
        slope = weight / torch.where(same, c.collision_dist, c.collision_inter_group_dist)  # p / d
        return torch.relu(2 * weight - d * slope).sum((1, 2))  # one fused ramp for both kinds of pairs

    def collisions(self, state: EnvState) -> Tensor:
        """(B,) number of unordered pairs closer than the collision distance d_c."""
        d, _, upper = self._pair_geometry(state)
        return ((d < self.cfg.collision_dist) & upper).sum((1, 2)).to(d.dtype)

    def true_distance(self, state: EnvState) -> Tensor:
        """(B, N, N) noise-free pairwise distances, self excluded by +inf (the dist baseline's k-nearest)."""
        d = torch.cdist(state.pos, state.pos)
        return d.masked_fill(eye_mask(state.n_agents, d.device), float("inf"))
