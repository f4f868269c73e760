"""random-cross (paper section 4): up to four groups of 10 agents, placed on a circle of radius l, each flying to
the box opposite its start; one group is always present, each other one with probability 0.33 (N = 10 to 40).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

from ..errors import ConfigError, check as _check
from ..utils.lazy import LazyModule
from .formation import FormationConfig, FormationState, FormationTask

if TYPE_CHECKING:
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")


@dataclass
class CrossConfig(FormationConfig):
    """random-cross and two-groups-cross: the groups sit on a circle of radius l and cross to the opposite box."""

    _target_: str = "neurosym_cli.tasks.random_cross.RandomCrossTask"
    num_groups: int = 4
    """possible groups (4 = paper random-cross, 2 = two-groups-cross)"""
    group_prob: float = 0.33
    """probability that each non-guaranteed group is present (paper section 4; one group always is)"""

    @property
    def max_agents(self) -> int:
        """N of the largest episode (every group present)."""
        return self.num_groups * self.agents_per_group

    def __post_init__(self) -> None:
        super().__post_init__()
        _check(self.num_groups >= 1, "task.num_groups must be positive")
        _check(0.0 <= self.group_prob <= 1.0, "task.group_prob must lie in [0, 1]")


class RandomCrossTask(FormationTask):
    """Cross layout: group k starts at R(2 pi k / G) (-l, 0) and flies to the opposite box."""

    Config = CrossConfig

    @cached_property
    def start_centers(self) -> Tensor:
        """(G, 2) box centres where the groups start (reference tasks/random_cross.py)."""
        g = self.cfg.num_groups
        ang = torch.tensor([2 * math.pi * k / g for k in range(g)], dtype=torch.float64)
        # group k starts at R(theta_k) (-l, 0) and flies to the opposite box
        return (torch.stack([-torch.cos(ang), -torch.sin(ang)], -1) * self.cfg.ell).float()

    @property
    def goal_centers(self) -> Tensor:
        return -self.start_centers

    def _cross_centers(self, present: Tensor) -> tuple[Tensor, Tensor]:
        """present: (E, G) bool with the same count per row -> start/goal centres (E, g, 2)."""
        idx = torch.nonzero(present)[:, 1].reshape(present.shape[0], -1)  # (E, g) present groups in index order
        return self.start_centers[idx], self.goal_centers[idx]

    def reset(self, batch: int, gen: torch.Generator) -> list[FormationState]:
        """Sample ``batch`` random episodes, returned as buckets of equal agent count."""
        c = self.cfg
        g = c.num_groups
        # one group always present, the others independently (docs/fidelity.md: an empty episode is meaningless)
        present = torch.rand(batch, g, generator=gen) < c.group_prob
        present[torch.arange(batch), torch.randint(0, g, (batch,), generator=gen)] = True
        counts = present.sum(1)
        buckets = []
        for k in sorted(set(counts.tolist())):
            buckets.append(self._bucket(*self._cross_centers(present[counts == k]), gen))
        return buckets

    def setting(self, name: str, gen: torch.Generator) -> FormationState:
        """One episode of a fixed test setting: the present groups, as in '0-2'."""
        try:
            groups = sorted({int(t) for t in name.split("-")})
        except ValueError:
            raise ConfigError(f"cross setting {name!r}: expected group indices like '0-2'") from None
        if not groups or groups[-1] >= self.cfg.num_groups or groups[0] < 0:
            raise ConfigError(f"cross setting {name!r}: groups must lie in 0..{self.cfg.num_groups - 1}")
        present = torch.zeros(1, self.cfg.num_groups, dtype=torch.bool)
        present[0, groups] = True
        return self._bucket(*self._cross_centers(present), gen)
