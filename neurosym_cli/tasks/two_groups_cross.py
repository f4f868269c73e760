"""two-groups-cross (paper Figure 1): two groups of 10 agents cross, each to the other's start box; one group is
always present, the other with probability group_prob (N = 10 or 20). The cross layout of random-cross with two
groups, a task of its own so that the figure's setting is one command away."""

from __future__ import annotations

from ..errors import ConfigError
from .random_cross import CrossConfig, RandomCrossTask


class TwoGroupsCrossTask(RandomCrossTask):
    """random-cross's dynamics and sampling with exactly two groups, facing each other across the origin.
    `neurosym figures` draws the paper's Figure 1 for it (``figure1 = True``)."""

    figure1 = True

    def __init__(self, cfg: CrossConfig, horizon: int | None = None):
        if cfg.num_groups != 2:
            raise ConfigError(f"two-groups-cross has two groups, got task.num_groups={cfg.num_groups}")
        super().__init__(cfg, horizon)
