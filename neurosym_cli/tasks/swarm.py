"""swarm: two fronts of agents cross through each other, a formation task whose world grows with the team.

Groups start in blocks on two fronts facing each other across a gap: even groups on the south front, odd groups on
the north front, side by side along x. Each agent flies to a slot of the block opposite its own (its block mirrored
across the x axis), so every group crosses through the group facing it. A block has a fixed depth and a fixed
density, so its length, and the world, grow linearly with the group: the distance an agent flies, and how crowded
its neighbourhood is, do not depend on N (docs/fidelity.md, 'swarm'). Dynamics, costs, observation and features are
the formation tasks' (tasks/formation.py); from ``task.sparse_from`` agents on they run on the sparse path
(tasks/pairs.py), which is what makes 10,000 agents fit.

Starts and goals are drawn on a jittered lattice of spacing a = 1 / sqrt(density): each agent takes a random slot
and moves from it by up to (a - min_separation) / 2 along each axis, so any two are at least min_separation apart
and drawing N of them costs O(N) (the rejection sampling of the paper's tasks compares all pairs of a box).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..errors import check as _check
from ..utils.lazy import LazyModule
from .formation import FormationConfig, FormationState, FormationTask

if TYPE_CHECKING:
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")


@dataclass
class SwarmConfig(FormationConfig):
    """swarm: groups of any size on two facing fronts cross to the block opposite their own (tasks/swarm.py)."""

    _target_: str = "neurosym_cli.tasks.swarm.SwarmTask"
    num_groups: int = 2
    """groups (any number >= 1): even ones start on the south front, odd ones on the north front"""
    density: float = 1.0
    """agents per square world unit in a block (the lattice spacing is 1 / sqrt(density))"""
    depth: float = 6.0
    """world units: depth of a block across the front (its length is agents / (density depth))"""
    gap: float = 4.0
    """world units between the two fronts"""

    @property
    def max_agents(self) -> int:
        """N of every episode: every group is present."""
        return self.num_groups * self.agents_per_group

    @property
    def spacing(self) -> float:
        """a, world units: the lattice spacing."""
        return 1.0 / math.sqrt(self.density)

    def __post_init__(self) -> None:
        super().__post_init__()
        _check(self.num_groups >= 1, "task.num_groups must be positive")
        _check(self.density > 0 and self.depth > 0 and self.gap >= 0,
               "task.density and task.depth must be positive and task.gap non-negative")
        _check(self.spacing >= self.min_separation, f"task.density={self.density:g} packs agents "
               f"{self.spacing:.3g} apart, closer than task.min_separation={self.min_separation:g}: lower the "
               f"density to at most {1 / self.min_separation ** 2:g}")


class SwarmTask(FormationTask):
    """Two fronts crossing; one bucket per reset (every episode has N = num_groups x agents_per_group)."""

    Config = SwarmConfig

    def __init__(self, cfg: SwarmConfig, horizon: int | None = None):
        super().__init__(cfg, horizon)
        a = cfg.spacing
        self.rows = max(1, int(cfg.depth / a + 1e-9))  # lattice rows across the front
        self.cols = math.ceil(cfg.agents_per_group / self.rows)  # and along it

    def block_origins(self) -> tuple[Tensor, Tensor]:
        """(G, 2) the lower-left lattice slot of each group's start block and (G, 2) of its goal block, world units."""
        c = self.cfg
        a = c.spacing
        length = self.cols * a  # a block's extent along x, one spacing between blocks
        per_side = [math.ceil(c.num_groups / 2), c.num_groups // 2]
        start = []
        for k in range(c.num_groups):
            side, m = k % 2, k // 2
            x0 = (m - per_side[side] / 2) * (length + a) + a / 2
            y_near = c.gap / 2 + a / 2  # the row nearest the gap
            y0 = -(y_near + (self.rows - 1) * a) if side == 0 else y_near
            start.append((x0, y0))
        s = torch.tensor(start)
        goal = torch.stack([s[:, 0], -s[:, 1] - (self.rows - 1) * a], -1)  # the block mirrored across y = 0
        return s, goal

    def _slots(self, batch: int, gen: torch.Generator) -> tuple[Tensor, Tensor]:
        """(B, G n) start and goal lattice slots as (column, row) pairs, each (B, G n, 2) long: every agent of a group
        a distinct random slot of its block, and as its goal a random row of the same column of the opposite block
        (a random permutation of the rows per column, so goals are distinct too and the flight is straight across:
        its length does not grow with N)."""
        g, n = self.cfg.num_groups, self.cfg.agents_per_group
        pick = torch.rand(batch, g, self.rows * self.cols, generator=gen).argsort(-1)[..., :n]  # (B, G, n)
        col, row = pick // self.rows, pick % self.rows
        perm = torch.rand(batch, g, self.cols, self.rows, generator=gen).argsort(-1)  # (B, G, cols, rows)
        goal_row = perm.gather(3, row.unsqueeze(-1).view(batch, g, 1, n).expand(-1, -1, self.cols, -1))
        goal_row = goal_row.gather(2, col.view(batch, g, 1, n))[:, :, 0]  # (B, G, n): perm[col, row]
        return (torch.stack([col, row], -1).reshape(batch, g * n, 2),
                torch.stack([col, goal_row], -1).reshape(batch, g * n, 2))

    def _place(self, origin: Tensor, slots: Tensor, gen: torch.Generator) -> Tensor:
        """origin (G, 2) block corners, slots (B, G n, 2) long -> (B, G n, 2) positions: the slot jittered by at most
        (a - min_separation) / 2 along each axis."""
        c = self.cfg
        a = c.spacing
        b = slots.shape[0]
        corner = origin.repeat_interleave(c.agents_per_group, 0)  # (G n, 2)
        jitter = (torch.rand(b, slots.shape[1], 2, generator=gen) * 2 - 1) * ((a - c.min_separation) / 2)
        return corner + slots.float() * a + jitter

    def reset(self, batch: int, gen: torch.Generator) -> list[FormationState]:
        start, goal = self.block_origins()
        here, there = self._slots(batch, gen)
        pos, goals = self._place(start, here, gen), self._place(goal, there, gen)
        g, n = self.cfg.num_groups, self.cfg.agents_per_group
        group = torch.arange(g).repeat_interleave(n).expand(batch, -1).clone()
        return [FormationState(pos, goals, group)]

    def setting(self, name: str, gen: torch.Generator) -> FormationState:
        """swarm has no fixed test settings: every evaluation episode is a random one (``eval_episodes``)."""
        from ..errors import ConfigError

        raise ConfigError(f"swarm has no test setting {name!r}: leave task.test_settings empty")
