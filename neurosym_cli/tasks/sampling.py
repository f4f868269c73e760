"""Vectorised rejection sampling of points in boxes with a minimum separation."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..utils.lazy import LazyModule

if TYPE_CHECKING:
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")


def sample_in_boxes(
    centers: Tensor, n: int, half_width: float, min_sep: float, gen: torch.Generator, max_rounds: int = 100
) -> Tensor:
    """Draw n points uniformly in each axis-aligned square box, at least ``min_sep`` apart.

    centers: (M, 2) box centres, world units. Returns (M, n, 2).
    All boxes are sampled at once: every round redraws the points that lie too close to an earlier point of
    their box. After ``max_rounds`` the remaining points are kept as they are (as the reference does after
    100 n attempts), so the call always terminates.
    """
    m = centers.shape[0]
    pts = centers[:, None, :] + (torch.rand(m, n, 2, generator=gen) * 2 - 1) * half_width  # (M, n, 2)
    earlier = torch.ones(n, n, dtype=torch.bool).tril(-1)  # (n, n): [j, i] True when i < j
    for _ in range(max_rounds):
        d = torch.cdist(pts, pts)  # (M, n, n)
        bad = ((d < min_sep) & earlier).any(-1)  # (M, n): too close to an earlier point
        if not bool(bad.any()):
            break
        fresh = centers[:, None, :] + (torch.rand(m, n, 2, generator=gen) * 2 - 1) * half_width
        pts = torch.where(bad[..., None], fresh, pts)
    return pts
