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

    from .pairs import Offsets
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
    sparse_from: int = 256
    """teams of at least this many agents take the sparse path (tasks/pairs.py): o_ij computed where read with
    counter-based noise, collisions by a cell list, nearest neighbours by chunked scans. Smaller teams keep the
    dense tensors and the dense noise stream (the paper tasks' numbers, N <= 40, are bitwise unchanged); the
    collision values agree to float rounding either way (docs/performance.md, section 15)"""

    def __post_init__(self) -> None:
        super().__post_init__()
        _check(self.noise_std >= 0.0, "task.noise_std must be non-negative")
        # bounded above: a step of more than a second, or a speed beyond 100 world units a second (the arenas are
        # tens of units wide), overflows the squared-distance losses within an episode instead of training
        _check(0 < self.dt <= 1.0, f"task.dt must lie in (0, 1] seconds, got {self.dt}")
        _check(0 < self.v_max <= 100.0, f"task.v_max must lie in (0, 100] world units per second, got {self.v_max}")
        _check(self.sparse_from >= 0, "task.sparse_from must be non-negative (0: always the sparse path)")


def relative_observation(pos: Tensor, noise_std: float, rng: Rng, sparse_from: int | None = None
                         ) -> "Tensor | Offsets":
    """(B, N, N, 2) o_ij = x_j - x_i + eps_ij: agent i's noisy view of agent j (paper section 2). From
    ``sparse_from`` agents on, the same offsets as a pair source computed where read (one key per episode drawn
    from ``rng``, tasks/pairs.py) instead of the dense tensor."""
    b, n = pos.shape[0], pos.shape[1]
    if sparse_from is not None and n >= sparse_from:
        from .pairs import Offsets

        return Offsets(pos, noise_std, rng.keys(b))
    rel = pos[:, None, :, :] - pos[:, :, None, :]  # [i, j] = x_j - x_i
    if noise_std > 0:
        rel = rel + noise_std * rng.randn(b, n, n, 2)
    return rel


def collision_count(pos: Tensor, dist: float, sparse_from: int | None = None) -> Tensor:
    """(B,) number of unordered pairs of agents closer than ``dist``; from ``sparse_from`` agents on by a cell
    list (tasks/pairs.py)."""
    if sparse_from is not None and pos.shape[1] >= sparse_from:
        return close_pair_count(pos, dist)
    d = torch.cdist(pos, pos)
    upper = torch.ones_like(d[0], dtype=torch.bool).triu(1)
    return ((d < dist) & upper).sum((1, 2)).to(d.dtype)


def close_pair_count(pos: Tensor, dist: float) -> Tensor:
    """(B,) float: unordered pairs closer than ``dist`` (safe_norm distances), by the cell list."""
    from .pairs import close_pairs

    first, _ = close_pairs(pos, dist)
    return torch.bincount(first // pos.shape[1], minlength=pos.shape[0]).to(pos.dtype)
