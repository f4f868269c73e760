"""comm-range: hear every agent within a radius, the communication topology of BenchMARL's GNN models
(``topology="from_pos"``, an edge between agents closer than ``edge_radius``), as a fixed rule under the shared
transformer."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..errors import check
from .families import OwnRule

if TYPE_CHECKING:
    from torch import Tensor

    from ..config import RunConfig
    from ..policy.comm import CommContext


@dataclass
class CommRange(OwnRule):
    """comm-range: its own transformer, each agent hearing every other agent within ``radius`` (noise-free
    distances, as dist); the degree varies with the crowd, from nobody to everybody."""

    radius: float = 1.5
    """world units: an agent hears every agent at most this far away. 1.5 is about the width of a formation task's
    start box (half-width 1.25, starts at least 0.5 apart): a group starts hearing most of itself and nobody of
    the other groups (docs/fidelity.md, 'Communication range')"""

    def __post_init__(self) -> None:
        check(self.radius > 0, f"baseline.radius must be positive, got {self.radius}")

    def tag(self, cfg: "RunConfig") -> str:
        return f"r{self.radius:g}"

    def train_overrides(self, cfg: "RunConfig") -> str:
        return f" baseline.radius={self.radius:g}"

    def mask(self, ctx: "CommContext", round: int) -> "Tensor":
        # The dense path (picks None): at N = 40 a step is faster with the (B, N, N) mask than with picks padded
        # to the largest degree of the batch (-1 = nobody), which pay a sort per step and gather up to N - 1 pairs
        # anyway (benchmarks/bench_comm_paths.py --range; measured in the commit that added this scheme).
        return ctx.env.true_distance(ctx.state) <= self.radius  # (B, N, N); +inf on the diagonal: never itself
