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
    distances, as dist); the degree varies with the crowd, from nobody to everybody (edge weights and the
    distance as an edge feature, which BenchMARL's GNN may add, are not: the transformer's attention weighs them)."""

    radius: float = 1.5
    """world units: an agent hears every agent at most this far away. 1.5 is about the width of a formation task's
    start box (half-width 1.25, starts at least 0.5 apart): a group starts hearing most of itself and nobody of
    the other groups (docs/fidelity.md, 'Communication range')"""

    def __post_init__(self) -> None:
        super().__post_init__()
        check(self.radius > 0, f"baseline.radius must be positive, got {self.radius}")

    def tag(self, cfg: "RunConfig") -> str:
        return f"r{self.radius:g}"

    def train_overrides(self, cfg: "RunConfig") -> str:
        return f" baseline.radius={self.radius:g}"

    def mask(self, ctx: "CommContext", round: int) -> "Tensor":
        from ..tasks.base import require

        d = require(ctx.env, "distances", "comm-range")(ctx.state)  # (B, N, N); +inf on the diagonal
        return d <= self.radius  # never itself

    def picks(self, ctx: "CommContext", round: int) -> "Tensor":
        """(B, N, K) the agents within the radius, padded with -1 (nobody) to K, the batch's largest degree."""
        # The sparse path, picks padded to the batch's largest degree, not the dense (B, N, N) mask: at N = 40
        # (random-cross with every group present, 8 episodes, T = 200, one thread) a training step took 4.4-6.0 s
        # padded against 4.5-7.4 s dense in four paired runs on a busy 2-core machine (1.0x-1.85x, median 1.2x),
        # since the degree stays far below N - 1 (benchmarks/bench_comm_paths.py --set task.group_prob=1)
        if ctx.obs.pairs is not None:  # a large team: the cell list's neighbours, no (B, N, N) distances
            from ..tasks.pairs import within

            return within(ctx.state.pos, self.radius)
        near = self.mask(ctx, round)
        k = int(near.sum(-1).max())
        heard, idx = near.to(ctx.obs.agent.dtype).topk(k, dim=-1)  # any order: the transformer dedups picks
        return idx.masked_fill(heard == 0, -1)
