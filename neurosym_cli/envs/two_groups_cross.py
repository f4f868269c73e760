"""two-groups-cross (paper Figure 1): two groups of 10 agents cross, each to the other's start box; one group is
always present, the other with probability group_prob (N = 10 or 20). The cross layout of random-cross with two
groups, a task of its own so that the figure's setting is one command away."""

from __future__ import annotations

from ..config import ConfigError, CrossConfig
from .random_cross import RandomCrossEnv


class TwoGroupsCrossEnv(RandomCrossEnv):
    """random-cross's dynamics and sampling with exactly two groups, facing each other across the origin."""

    def __init__(self, cfg: CrossConfig, horizon: int | None = None):
        if cfg.num_groups != 2:
            raise ConfigError(f"two-groups-cross has two groups, got task.num_groups={cfg.num_groups}")
        super().__init__(cfg, horizon)
