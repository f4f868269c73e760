"""What a VMAS task computes from its state: the 2-D vectors of the agent observation (and their features), and
the differentiable per-step costs with the success metrics of their scenarios (docs/vmas.md, 'Costs')."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

from ...utils.lazy import LazyModule
from ..base import safe_norm
from .world import VmasState

if TYPE_CHECKING:
    import torch
    from torch import Tensor

    from .task import VmasTask
else:
    torch = LazyModule("torch")


@dataclass(frozen=True)
class Vector:
    """A 2-D vector of the asking agent, computed from the state: its feature prefix, words, and what it needs."""

    prefix: str
    owner: str  # the phrase of its features' words ("my goal" -> "my distance to my goal")
    fn: Callable[["VmasTask", VmasState], "Tensor"]  # -> (B, N, 2)
    needs: str = ""  # what the scenario must have (the one-line refusal quotes it)


def _nearest_landmark(task: "VmasTask", s: VmasState) -> Tensor:
    off = s.lm_pos[:, None, :, :] - s.pos[:, :, None, :]  # (B, N, L, 2)
    k = off.norm(dim=-1).argmin(-1)  # (B, N)
    return torch.gather(off, 2, k[..., None, None].expand(-1, -1, 1, 2)).squeeze(2)


VECTORS: dict[str, Vector] = {
    "goal": Vector("g", "my goal", lambda t, s: t.goal_pos(s) - s.pos, "agents with a `goal` landmark"),
    "nearest_landmark": Vector("l", "the nearest landmark", _nearest_landmark, "at least one landmark"),
    "position": Vector("p", "position", lambda t, s: s.pos),
}
"""task.vectors -> the vector: s_i starts with these (2 columns each), then the velocity, then the scenario's own"""


@dataclass(frozen=True)
class Objective:
    """A differentiable per-step cost (B,) and the success metrics of the scenarios it belongs to."""

    cost: Callable[["VmasTask", VmasState], "Tensor"]
    metrics: Callable[["VmasTask", VmasState], dict[str, "Tensor"]]
    needs: str = ""  # a VECTORS key the objective reads (goal), checked like the vectors


def _goal_distance(t: "VmasTask", s: VmasState) -> Tensor:
    """navigation: sum_i |x_i - g_i|. VMAS's reward is the potential difference d_{t-1} - d_t (shared); its negated
    sum over an episode telescopes to d_T - d_0 and rewards only the end; the potential itself, summed over the
    horizon, is the same return accumulated at every step (plus a constant) and rewards arriving early."""
    return safe_norm(s.pos - t.goal_pos(s)).sum(-1)


def _on_goal(t: "VmasTask", s: VmasState) -> dict[str, Tensor]:
    """on_goal: fraction of agents within their goal's radius (VMAS's on_goal); success: all of them (VMAS's done)."""
    on = (s.pos - t.goal_pos(s)).norm(dim=-1) < t.lm_radius_of_goals(s)
    return {"on_goal": on.float().mean(-1), "success": on.all(-1).float()}


def _coverage(t: "VmasTask", s: VmasState) -> Tensor:
    """dispersion: sum over food of the distance to its nearest agent. VMAS's reward is an indicator (eating) with
    zero gradient; this potential is zero exactly when every food item has an agent on it."""
    return safe_norm(s.lm_pos[:, :, None, :] - s.pos[:, None, :, :]).min(-1).values.sum(-1)


def _covered(t: "VmasTask", s: VmasState) -> dict[str, Tensor]:
    """covered: fraction of food with an agent on it (VMAS's eating condition, d < r_agent + r_food)."""
    d = (s.lm_pos[:, :, None, :] - s.pos[:, None, :, :]).norm(dim=-1)  # (B, L, N)
    r = t.radius(s)[:, None, :] + t.lm_radius(s)[:, :, None]
    on = (d < r).any(-1)
    return {"covered": on.float().mean(-1), "success": on.all(-1).float()}


OBJECTIVES: dict[str, Objective] = {
    "goal_distance": Objective(_goal_distance, _on_goal, needs="goal"),
    "coverage": Objective(_coverage, _covered),
    "reward": Objective(lambda t, s: -s.reward.sum(-1), lambda t, s: {}),
}
"""task.cost -> the objective (docs/vmas.md, 'Costs'); every one adds the named shaping collision_weight"""

