"""Differentiable batched environments, one file per task over shared parts, and their registry.

    base.py              the functional env interface, EnvState, shape letters, random sources
    formation.py         formation flying: dynamics, observation, cost and collisions shared by three tasks
    random_cross.py      random-cross (paper section 4)
    two_groups_cross.py  two-groups-cross (paper Figure 1)
    random_grid.py       random-grid (paper section 4)
    unlabeled_goals.py   unlabeled-goals (paper section 4, two communication rounds)
    features.py          the programs' feature map phi(s_i, o_ij) (section 3.2)
"""

from __future__ import annotations

from typing import Callable

from ..config import ConfigError, TaskConfig
from .base import EnvState, MultiAgentEnv, Observation, Rng
from .formation import FormationEnv
from .random_cross import RandomCrossEnv
from .random_grid import RandomGridEnv
from .two_groups_cross import TwoGroupsCrossEnv
from .unlabeled_goals import UnlabeledGoalsEnv

ENVS: dict[str, Callable[..., MultiAgentEnv]] = {
    "random-cross": RandomCrossEnv,
    "two-groups-cross": TwoGroupsCrossEnv,
    "random-grid": RandomGridEnv,
    "unlabeled-goals": UnlabeledGoalsEnv,
}
"""task.env -> environment class"""


def make_env(cfg: TaskConfig, horizon: int | None = None) -> MultiAgentEnv:
    """Build the environment of a task config; ``horizon`` overrides the task's T."""
    if cfg.env not in ENVS:
        raise ConfigError(f"unknown task.env {cfg.env!r}; known: {', '.join(ENVS)}")
    return ENVS[cfg.env](cfg, horizon)


__all__ = ["ENVS", "EnvState", "FormationEnv", "MultiAgentEnv", "Observation", "Rng", "RandomCrossEnv",
           "RandomGridEnv", "TwoGroupsCrossEnv", "UnlabeledGoalsEnv", "make_env"]
