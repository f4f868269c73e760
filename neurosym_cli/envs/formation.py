"""Formation flying (paper section 4): agents in groups fly from start boxes to goal boxes without colliding.

Layouts: ``cross`` (random-cross, two-groups-cross) and ``grid`` (random-grid). Constants follow
decisions.md; every one of them is a field of :class:`~neurosym_cli.config.TaskConfig`.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

from ..config import ConfigError, TaskConfig
from .base import EnvState, EpisodeSeeder, Observation, Rng, clip_speed, eye_mask, safe_norm
from .sampling import sample_in_boxes

# random-grid goal choices of the side groups (reference tasks/random_grid.py)
UP, DOWN, MID = 0, 1, 2


class FormationEnv:
    """Batched formation flying. Agent input s_i = x_i - g_i (obs_dim 2); action = velocity (A = 2)."""

    obs_dim = 2
    action_dim = 2

    def __init__(self, cfg: TaskConfig, horizon: int | None = None):
        self.cfg = cfg
        self.horizon = horizon or cfg.horizon
        self.n = cfg.agents_per_group
        if cfg.layout == "cross":
            g = cfg.num_groups
            ang = torch.tensor([2 * math.pi * k / g for k in range(g)], dtype=torch.float64)
            # group k starts at R(theta_k) (-l, 0) and flies to the opposite box (reference tasks/random_cross.py)
            self.start_centers = (torch.stack([-torch.cos(ang), -torch.sin(ang)], -1) * cfg.ell).float()  # (G, 2)
            self.goal_centers = -self.start_centers
        else:
            l = cfg.ell
            self.start_centers = torch.tensor([[-l, 0.0], [l, 0.0], [0.0, 0.0]])  # left, right, middle
            self.left_goals = torch.tensor([[-l, l], [-l, -l], [0.0, 0.0]])  # UP, DOWN, MID
            self.right_goals = torch.tensor([[l, l], [l, -l], [0.0, 0.0]])
            self.mid_goals = torch.tensor([[-l, 0.0], [l, 0.0]])  # LEFT, RIGHT

    # ----------------------------------------------------------------------------------------- sampling
    def _bucket(self, start_c: Tensor, goal_c: Tensor, gen: torch.Generator) -> EnvState:
        """start_c, goal_c: (E, g, 2) box centres of the g groups of E episodes -> EnvState with N = g n."""
        e, g, _ = start_c.shape
        c = self.cfg
        starts = sample_in_boxes(start_c.reshape(-1, 2), self.n, c.box_half_width, c.min_separation, gen)
        goals = sample_in_boxes(goal_c.reshape(-1, 2), self.n, c.box_half_width, c.min_separation, gen)
        group = torch.arange(g).repeat_interleave(self.n).expand(e, -1)  # (E, N)
        return EnvState(starts.reshape(e, g * self.n, 2), goals.reshape(e, g * self.n, 2), group.clone())

    def _cross_centers(self, present: Tensor) -> tuple[Tensor, Tensor]:
        """present: (E, G) bool with the same count per row -> start/goal centres (E, g, 2)."""
        idx = torch.nonzero(present)[:, 1].reshape(present.shape[0], -1)  # (E, g) present groups in index order
        return self.start_centers[idx], self.goal_centers[idx]

    def _grid_centers(self, left: Tensor, mid: Tensor, right: Tensor) -> tuple[Tensor, Tensor]:
        e = left.shape[0]
        start = self.start_centers.expand(e, 3, 2)
        goal = torch.stack([self.left_goals[left], self.right_goals[right], self.mid_goals[mid]], 1)  # (E, 3, 2)
        return start, goal

    def reset(self, batch: int, gen: torch.Generator) -> list[EnvState]:
        """Sample ``batch`` random episodes, returned as buckets of equal agent count."""
        c = self.cfg
        if c.layout == "grid":
            mid = torch.randint(0, 2, (batch,), generator=gen)
            side = torch.where(torch.rand(batch, 2, generator=gen) < 0.5, MID, torch.randint(0, 2, (batch, 2), generator=gen))
            # the paper's constraint: goal boxes are distinct, so both sides cannot go to the middle
            both = (side == MID).all(1)
            redraw = torch.randint(0, 2, (batch,), generator=gen)  # which side is redrawn
            updown = torch.randint(0, 2, (batch,), generator=gen)
            side[both, redraw[both]] = updown[both]
            return [self._bucket(*self._grid_centers(side[:, 0], mid, side[:, 1]), gen)]
        g = c.num_groups
        # one group always present, the others independently (decisions.md: an empty episode is meaningless)
        present = torch.rand(batch, g, generator=gen) < c.group_prob
        present[torch.arange(batch), torch.randint(0, g, (batch,), generator=gen)] = True
        counts = present.sum(1)
        buckets = []
        for k in sorted(set(counts.tolist())):
            buckets.append(self._bucket(*self._cross_centers(present[counts == k]), gen))
        return buckets

    def setting(self, name: str, gen: torch.Generator) -> EnvState:
        """One episode of a fixed test setting: cross '0-2' (present groups), grid 'rlu' (left, mid, right)."""
        if self.cfg.layout == "cross":
            try:
                groups = sorted({int(t) for t in name.split("-")})
            except ValueError:
                raise ConfigError(f"cross setting {name!r}: expected group indices like '0-2'") from None
            if not groups or groups[-1] >= self.cfg.num_groups or groups[0] < 0:
                raise ConfigError(f"cross setting {name!r}: groups must lie in 0..{self.cfg.num_groups - 1}")
            present = torch.zeros(1, self.cfg.num_groups, dtype=torch.bool)
            present[0, groups] = True
            return self._bucket(*self._cross_centers(present), gen)
        codes = {"l": {"u": UP, "d": DOWN, "r": MID}, "m": {"l": 0, "r": 1}, "r": {"u": UP, "d": DOWN, "l": MID}}
        if len(name) != 3 or any(ch not in codes[k] for k, ch in zip("lmr", name)):
            raise ConfigError(f"grid setting {name!r}: expected left in u/d/r, mid in l/r, right in u/d/l (e.g. 'rlu')")
        left, mid, right = (torch.tensor([codes[k][ch]]) for k, ch in zip("lmr", name))
        return self._bucket(*self._grid_centers(left, mid, right), gen)

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
