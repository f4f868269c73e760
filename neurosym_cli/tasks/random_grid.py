"""random-grid (paper section 4): three groups start at (-l, 0), (0, 0) and (l, 0) and fly to adjacent, distinct
boxes of a 3 x 3 grid with spacing l = 14 (N = 30).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..errors import ConfigError
from ..utils.lazy import LazyModule
from .formation import FormationConfig, FormationState, FormationTask

if TYPE_CHECKING:
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")

# random-grid goal choices of the side groups (reference tasks/random_grid.py)
UP, DOWN, MID = 0, 1, 2


@dataclass
class GridConfig(FormationConfig):
    """random-grid: three groups start at (-l, 0), (0, 0), (l, 0) and fly to adjacent, distinct boxes of a 3x3 grid."""

    _target_: str = "neurosym_cli.tasks.random_grid.RandomGridTask"
    ell: float = 14.0

    @property
    def max_agents(self) -> int:
        """N of every episode: three groups."""
        return 3 * self.agents_per_group


class RandomGridTask(FormationTask):
    """Grid layout: the left and right groups go up, down or to the middle; the middle group goes left or right."""

    Config = GridConfig

    def _grid_centers(self, left: Tensor, mid: Tensor, right: Tensor) -> tuple[Tensor, Tensor]:
        l = self.cfg.ell
        start_centers = torch.tensor([[-l, 0.0], [l, 0.0], [0.0, 0.0]])  # left, right, middle
        left_goals = torch.tensor([[-l, l], [-l, -l], [0.0, 0.0]])  # UP, DOWN, MID
        right_goals = torch.tensor([[l, l], [l, -l], [0.0, 0.0]])
        mid_goals = torch.tensor([[-l, 0.0], [l, 0.0]])  # LEFT, RIGHT
        e = left.shape[0]
        start = start_centers.expand(e, 3, 2)
        goal = torch.stack([left_goals[left], right_goals[right], mid_goals[mid]], 1)  # (E, 3, 2)
        return start, goal

    def reset(self, batch: int, gen: torch.Generator) -> list[FormationState]:
        """Sample ``batch`` random episodes (one bucket: N = 30 in every episode)."""
        mid = torch.randint(0, 2, (batch,), generator=gen)
        side = torch.where(torch.rand(batch, 2, generator=gen) < 0.5, MID, torch.randint(0, 2, (batch, 2), generator=gen))
        # the paper's constraint: goal boxes are distinct, so both sides cannot go to the middle
        both = (side == MID).all(1)
        redraw = torch.randint(0, 2, (batch,), generator=gen)  # which side is redrawn
        updown = torch.randint(0, 2, (batch,), generator=gen)
        side[both, redraw[both]] = updown[both]
        return [self._bucket(*self._grid_centers(side[:, 0], mid, side[:, 1]), gen)]

    def setting(self, name: str, gen: torch.Generator) -> FormationState:
        """One episode of a fixed test setting: 'rlu' = left goes r(ight, the middle), middle goes l(eft), right
        goes u(p)."""
        codes = {"l": {"u": UP, "d": DOWN, "r": MID}, "m": {"l": 0, "r": 1}, "r": {"u": UP, "d": DOWN, "l": MID}}
        if len(name) != 3 or any(ch not in codes[k] for k, ch in zip("lmr", name)):
            raise ConfigError(f"grid setting {name!r}: expected left in u/d/r, mid in l/r, right in u/d/l (e.g. 'rlu')")
        left, mid, right = (torch.tensor([codes[k][ch]]) for k, ch in zip("lmr", name))
        return self._bucket(*self._grid_centers(left, mid, right), gen)
