"""What the paper's tasks share: agents in the plane that fly at a clipped speed and see each other's offsets."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..config import TaskConfig
from ..errors import check as _check
from ..utils.lazy import LazyModule
from .base import Rng

if TYPE_CHECKING:
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")


@dataclass
class PlanarConfig(TaskConfig):
    """Agents in the plane with single-integrator dynamics (paper section 4; docs/fidelity.md, 'Environments')."""

    dt: float = 0.1
    """seconds per step"""
    v_max: float = 2.0
    """world units per second: the speed is clipped to this norm"""
    noise_std: float = 0.05
    """world units: std of the Gaussian noise on relative observations o_ij"""
    collision_dist: float = 0.1
    """d_c, world units: pairs closer than this count as a collision (and the within-group ramp is zero beyond
    2 d_c)"""

    def __post_init__(self) -> None:
        super().__post_init__()
        _check(self.noise_std >= 0.0, "task.noise_std must be non-negative")
        # bounded above: a step of more than a second, or a speed beyond 100 world units a second (the arenas are
        # tens of units wide), overflows the squared-distance losses within an episode instead of training
        _check(0 < self.dt <= 1.0, f"task.dt must lie in (0, 1] seconds, got {self.dt}")
        _check(0 < self.v_max <= 100.0, f"task.v_max must lie in (0, 100] world units per second, got {self.v_max}")


def relative_observation(pos: Tensor, noise_std: float, rng: Rng) -> Tensor:
    """(B, N, N, 2) o_ij = x_j - x_i + eps_ij: agent i's noisy view of agent j (paper section 2)."""
    b, n = pos.shape[0], pos.shape[1]
    rel = pos[:, None, :, :] - pos[:, :, None, :]  # [i, j] = x_j - x_i
    if noise_std > 0:
        rel = rel + noise_std * rng.randn(b, n, n, 2)
    return rel


def collision_count(pos: Tensor, dist: float) -> Tensor:
    """(B,) number of unordered pairs of agents closer than ``dist``."""
    d = torch.cdist(pos, pos)
    upper = torch.ones_like(d[0], dtype=torch.bool).triu(1)
    return ((d < dist) & upper).sum((1, 2)).to(d.dtype)
