"""Unlabeled goals (paper section 4): N agents must cover N goals with no assignment given.

Each agent outputs weights p_i over the goals (in its own order: goals sorted by initial distance) and moves
along sum_k p_ik (g_k - x_i), speed clipped to v_max (paper; ``velocity=reference`` uses the reference's
v_max * sum_k p_ik unit(g_k - x_i)). The loss of a step is N - sum_k max_i p_ik: the number of uncovered goals
on the paper's plot scale (docs/fidelity.md).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..errors import check as _check
from ..utils.lazy import LazyModule
from .base import EpisodeSeeder, Observation, Rng, Scene, TaskState, clip_speed, pairwise_distances, safe_norm
from .features import Columns, FeatureMap, vector_map
from .planar import PlanarConfig, collision_count, relative_observation
from .sampling import sample_in_boxes

if TYPE_CHECKING:
    import torch
    from torch import Tensor

    from ..utils import ops
else:
    torch = LazyModule("torch")
    ops = LazyModule("neurosym_cli.utils.ops")


@dataclass
class UnlabeledConfig(PlanarConfig):
    """unlabeled-goals (section 4): N agents cover N goals with no assignment given."""

    _target_: str = "neurosym_cli.tasks.unlabeled_goals.UnlabeledGoalsTask"
    horizon: int = 100
    rounds: int = 2
    start_half_width: float = 2.0
    """starts are drawn in [-w, w]^2"""
    goal_half_width: float = 8.0
    """goals are drawn in [-w, w]^2"""
    start_separation: float = 1.0
    """minimum separation between starts"""
    goal_separation: float = 2.0
    """minimum separation between goals"""
    velocity: str = "paper"
    """paper (sum_k p_k (g_k - x)) or reference (v_max * sum_k p_k unit(g_k - x))"""

    @property
    def max_agents(self) -> int:
        """N of every episode (as many agents as goals)."""
        return self.agents_per_group

    def __post_init__(self) -> None:
        super().__post_init__()
        _check(self.velocity in ("paper", "reference"), "task.velocity must be paper or reference")


@dataclass(frozen=True)
class UnlabeledState(TaskState):
    """A bucket of unlabeled-goals episodes."""

    goal: Tensor  # (B, G, 2) the goal set, world units
    goal_order: Tensor  # (B, N, G) long: each agent's goals sorted by their initial distance


class UnlabeledGoalsTask:
    """Agent input s_i = [x_i, x_i - g_sigma_i(1), ..., x_i - g_sigma_i(G)] (obs_dim 2 + 2G); o_ij = x_j - x_i + noise
    (pair_dim 2); action = G logits."""

    Config = UnlabeledConfig
    pair_dim = 2

    def __init__(self, cfg: UnlabeledConfig, horizon: int | None = None):
        self.cfg = cfg
        self.horizon = horizon or cfg.horizon
        self.rounds = cfg.rounds
        self.n = cfg.agents_per_group
        self.obs_dim = 2 + 2 * self.n
        self.action_dim = self.n

    def reset(self, batch: int, gen: torch.Generator) -> list[UnlabeledState]:
        c = self.cfg
        zeros = torch.zeros(batch, 2)
        pos = sample_in_boxes(zeros, self.n, c.start_half_width, c.start_separation, gen)  # (B, N, 2)
        goal = sample_in_boxes(zeros, self.n, c.goal_half_width, c.goal_separation, gen)  # (B, G, 2)
        # each agent orders the goals by their distance at t = 0; the order is fixed for the episode
        order = torch.cdist(pos, goal).argsort(-1)  # (B, N, G)
        return [UnlabeledState(pos, goal, order)]

    def test_episodes(self, seeder: EpisodeSeeder) -> tuple[list[UnlabeledState], list[torch.Generator]]:
        """``eval_episodes`` random episodes of one evaluation seed, each with its own generator."""
        gens = [seeder(k) for k in range(self.cfg.eval_episodes)]
        return [self.reset(1, g)[0] for g in gens], gens

    def observe(self, state: UnlabeledState, rng: Rng) -> Observation:
        n = state.n_agents
        sorted_goals = torch.gather(state.goal[:, None].expand(-1, n, -1, -1), 2,
                                    state.goal_order[..., None].expand(-1, -1, -1, 2))  # (B, N, G, 2)
        offsets = (state.pos[:, :, None, :] - sorted_goals).flatten(2)  # (B, N, 2G)
        rel = relative_observation(state.pos, self.cfg.noise_std, rng)
        return Observation(agent=torch.cat([state.pos, offsets], -1), rel=rel)

    def goal_weights(self, state: UnlabeledState, action: Tensor) -> Tensor:
        """(B, N, G) softmax weights indexed by absolute goal id (the action is in each agent's own order)."""
        p = ops.softmax_last(action)
        return torch.zeros_like(p).scatter(-1, state.goal_order, p)

    def target(self, action: Tensor) -> Tensor:
        """(B, N, G) the goal weights p_i: what synthesis imitates."""
        return ops.softmax_last(action)

    def step(self, state: UnlabeledState, action: Tensor) -> UnlabeledState:
        p = self.goal_weights(state, action)  # (B, N, G)
        to_goal = state.goal[:, None, :, :] - state.pos[:, :, None, :]  # (B, N, G, 2)
        if self.cfg.velocity == "reference":
            v = self.cfg.v_max * (p[..., None] * to_goal / safe_norm(to_goal)[..., None]).sum(2)
        else:
            v = (p[..., None] * to_goal).sum(2)
        v = clip_speed(v, self.cfg.v_max)
        return dataclasses.replace(state, pos=state.pos + self.cfg.dt * v)

    def cost(self, next_state: UnlabeledState, action: Tensor) -> Tensor:
        """(B,) uncovered goals: N - sum_k max_i p_ik."""
        p = self.goal_weights(next_state, action)
        return self.n - p.amax(1).sum(-1)

    def metrics(self, state: UnlabeledState) -> dict[str, Tensor]:
        """Per step, (B,) each: collisions (unordered pairs closer than d_c)."""
        return {"collisions": collision_count(state.pos, self.cfg.collision_dist)}

    def features(self, version: str) -> FeatureMap:
        """Position px py pd ptheta, and the k-th nearest goal by initial distance g{k}x ... g{k}theta (the goal
        vector g - x), and o_ij (dx dy d theta); v2 adds px_dx ... py_dy."""
        state = [("p", "position", Columns("agent", 0))]
        state += [(f"g{k + 1}", f"my goal {k + 1} (by initial distance)", Columns("agent", 2 + 2 * k, -1.0))
                  for k in range(self.n)]  # the input holds x - g; the feature is g - x
        return vector_map(state, version)

    def distances(self, state: UnlabeledState) -> Tensor:
        """(B, N, N) noise-free pairwise distances, self excluded by +inf (dist's k-nearest)."""
        return pairwise_distances(state.pos)

    def scene(self, state: UnlabeledState) -> Scene:
        return Scene(goal=state.goal[0], group=torch.zeros(state.n_agents, dtype=torch.long), labelled=False)
