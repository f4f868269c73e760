"""Formation flying (paper section 4): agents in groups fly from start boxes to goal boxes without colliding.

The schema, state, dynamics, observation, cost and collisions shared by the formation tasks; each task's file says
where its groups start and where they go: random_cross.py, two_groups_cross.py, random_grid.py. Constants:
docs/fidelity.md; every one is a field of :class:`FormationConfig`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..utils.lazy import LazyModule
from .base import EpisodeSeeder, Observation, Rng, Scene, TaskState, clip_speed, pairwise_distances, safe_norm
from .features import Columns, FeatureMap, vector_map
from .planar import PlanarConfig, close_pair_count, relative_observation
from .sampling import sample_in_boxes

if TYPE_CHECKING:
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")


@dataclass
class FormationConfig(PlanarConfig):
    """Formation flying (section 4): groups fly from start boxes to goal boxes without colliding."""

    ell: float = 7.0
    """world units: distance from the origin to the group box centres (paper's l)"""
    box_half_width: float = 1.25
    """world units: half-width of the start and goal boxes"""
    min_separation: float = 0.5
    """world units: minimum distance between sampled start (and goal) points"""
    collision_weight: float = 5.0
    """p_c: within-group collision penalty weight"""
    collision_inter_group_weight: float = 25.0
    """reference code's across-group ramp weight (0 disables it; paper is silent)"""
    collision_inter_group_dist: float = 2.0
    """world units: across-group ramp distance"""


@dataclass(frozen=True)
class FormationState(TaskState):
    """A bucket of formation episodes."""

    goal: Tensor  # (B, N, 2) each agent's goal, world units
    group: Tensor  # (B, N) long: group index per agent


class FormationTask:
    """Batched formation flying. Agent input s_i = x_i - g_i (obs_dim 2); o_ij = x_j - x_i + noise (pair_dim 2);
    action = velocity (A = 2). A task subclass samples episodes (``reset``) and builds its fixed test settings
    (``setting``)."""

    Config = FormationConfig
    obs_dim = 2
    pair_dim = 2
    action_dim = 2

    def __init__(self, cfg: FormationConfig, horizon: int | None = None):
        self.cfg = cfg
        self.horizon = horizon or cfg.horizon
        self.rounds = cfg.rounds
        self.n = cfg.agents_per_group

    def reset(self, batch: int, gen: torch.Generator) -> list[FormationState]:
        """Sample ``batch`` random episodes, returned as buckets of equal agent count."""
        raise NotImplementedError

    def setting(self, name: str, gen: torch.Generator) -> FormationState:
        """One episode of a named fixed test setting."""
        raise NotImplementedError

    def with_team_size(self, n: int) -> "FormationTask":
        """The same task with ``n`` agents per group (`neurosym stress`: zero-shot at other team sizes)."""
        return type(self)(dataclasses.replace(self.cfg, agents_per_group=n), self.horizon)

    def _bucket(self, start_c: Tensor, goal_c: Tensor, gen: torch.Generator) -> FormationState:
        """start_c, goal_c: (E, g, 2) box centres of the g groups of E episodes -> a state with N = g n."""
        e, g, _ = start_c.shape
        c = self.cfg
        starts = sample_in_boxes(start_c.reshape(-1, 2), self.n, c.box_half_width, c.min_separation, gen)
        goals = sample_in_boxes(goal_c.reshape(-1, 2), self.n, c.box_half_width, c.min_separation, gen)
        group = torch.arange(g).repeat_interleave(self.n).expand(e, -1)  # (E, N)
        return FormationState(starts.reshape(e, g * self.n, 2), goals.reshape(e, g * self.n, 2), group.clone())

    def test_episodes(self, seeder: EpisodeSeeder) -> tuple[list[FormationState], list[torch.Generator]]:
        """The single-episode states of one evaluation seed: each test setting once (reference protocol), or
        ``eval_episodes`` random episodes. ``seeder(k)`` gives episode k its own generator, used for its initial
        state and later for its noise."""
        names = self.cfg.test_settings
        gens = [seeder(k) for k in range(len(names) if names else self.cfg.eval_episodes)]
        if names:
            return [self.setting(nm, g) for nm, g in zip(names, gens)], gens
        return [self.reset(1, g)[0] for g in gens], gens

    # ---------------------------------------------------------------------------------------- dynamics
    def observe(self, state: FormationState, rng: Rng) -> Observation:
        # o_ij before s_i: the order the graph is built in is the order autograd sums the gradients into x, and
        # every checkpoint was trained with this one
        rel = relative_observation(state.pos, self.cfg.noise_std, rng, self.cfg.sparse_from)
        return Observation(agent=state.pos - state.goal, rel=rel)

    def target(self, action: Tensor) -> Tensor:
        """(B, N, 2) the velocity actually flown (speed-clipped): what synthesis imitates."""
        return clip_speed(action, self.cfg.v_max)

    def step(self, state: FormationState, action: Tensor) -> FormationState:
        """action: (B, N, 2) desired velocity; the speed is clipped to v_max, x <- x + dt v."""
        v = clip_speed(action, self.cfg.v_max)
        return dataclasses.replace(state, pos=state.pos + self.cfg.dt * v)

    def cost(self, next_state: FormationState, action: Tensor) -> Tensor:
        """(B,) loss of one step: sum_i ||x_i - g_i|| plus the collision ramps (paper section 4)."""
        dist = safe_norm(next_state.pos - next_state.goal).sum(-1)
        return dist + self.collision_cost(next_state)

    def _pair_geometry(self, state: FormationState) -> tuple[Tensor, Tensor, Tensor]:
        n = state.n_agents
        d = safe_norm(state.pos[:, :, None, :] - state.pos[:, None, :, :])  # (B, N, N)
        same = state.group[:, :, None] == state.group[:, None, :]  # (B, N, N)
        upper = torch.ones(n, n, dtype=torch.bool, device=d.device).triu(1)  # unordered pairs i < j
        return d, same, upper

    def collision_cost(self, state: FormationState) -> Tensor:
        """(B,) ramp max(0, p (2 - d_ij / d)) over unordered pairs; across groups with the inter-group p, d. From
        ``sparse_from`` agents on over the pairs within the ramps' reach only (a cell list): the same terms, summed
        in another order."""
        c = self.cfg
        if state.n_agents >= c.sparse_from:
            return self._collision_cost_near(state)
        d, same, upper = self._pair_geometry(state)
        p_across = c.collision_inter_group_weight
        weight = torch.where(same, c.collision_weight, p_across) * upper  # (B, N, N): p of each pair, 0 off i < j
        slope = weight / torch.where(same, c.collision_dist, c.collision_inter_group_dist)  # p / d
        return torch.relu(2 * weight - d * slope).sum((1, 2))  # one fused ramp for both kinds of pairs

    def _ramp(self, same: Tensor) -> tuple[Tensor, Tensor]:
        """same (...) bool: the pair is of one group -> the ramp's weight p and slope p / d of each pair."""
        c = self.cfg
        weight = torch.where(same, c.collision_weight, c.collision_inter_group_weight)
        return weight, weight / torch.where(same, c.collision_dist, c.collision_inter_group_dist)

    @property
    def ramp_reach(self) -> float:
        """World units beyond which no ramp is positive: 2 d_c within groups, 2 d across (0: no ramp at all)."""
        c = self.cfg
        return max(2 * c.collision_dist if c.collision_weight else 0.0,
                   2 * c.collision_inter_group_dist if c.collision_inter_group_weight else 0.0)

    def _collision_cost_near(self, state: FormationState) -> Tensor:
        """The collision ramps over the pairs a cell list finds within ``ramp_reach`` (exact: a pair beyond it
        adds relu(<= 0) = 0 and no gradient in the dense sum)."""
        from .pairs import close_pairs, near_ramps

        b, n = state.batch, state.n_agents
        if self.ramp_reach <= 0:
            return torch.zeros(b, dtype=state.pos.dtype, device=state.pos.device)
        first, second = close_pairs(state.pos, self.ramp_reach)
        flat, grp = state.pos.reshape(-1, 2), state.group.reshape(-1)
        weight, slope = self._ramp(torch.tensor([True, False], device=flat.device))  # (2,): within a group, across
        return near_ramps(flat, first, second, grp[first] == grp[second], weight, slope, b, n)

    def metrics(self, state: FormationState) -> dict[str, Tensor]:
        """Per step, (B,) each: collisions, the number of unordered pairs closer than the collision distance d_c."""
        if state.n_agents >= self.cfg.sparse_from:
            return {"collisions": close_pair_count(state.pos, self.cfg.collision_dist)}
        d, _, upper = self._pair_geometry(state)
        return {"collisions": ((d < self.cfg.collision_dist) & upper).sum((1, 2)).to(d.dtype)}

    def features(self, version: str) -> FeatureMap:
        """The goal vector g_i - x_i (gx gy gd gtheta) and o_ij (dx dy d theta); v2 adds gx_dx ... gy_dy."""
        return vector_map([("g", "my goal", Columns("agent", 0, -1.0))], version)  # g - x = -(x - g)

    def distances(self, state: FormationState) -> Tensor:
        """(B, N, N) noise-free pairwise distances, self excluded by +inf (dist's k-nearest)."""
        return pairwise_distances(state.pos)

    def scene(self, state: FormationState) -> Scene:
        return Scene(goal=state.goal[0], group=state.group[0], labelled=True)
