"""Differentiable batched environments and their registry (one factory per task kind)."""

from __future__ import annotations

from typing import Callable

from ..config import ConfigError, TaskConfig
from .base import EnvState, MultiAgentEnv, Observation, Rng
from .formation import FormationEnv
from .unlabeled import UnlabeledGoalsEnv

ENVS: dict[str, Callable[[TaskConfig, int | None], MultiAgentEnv]] = {
    "formation": FormationEnv,
    "unlabeled": UnlabeledGoalsEnv,
}


def make_env(cfg: TaskConfig, horizon: int | None = None) -> MultiAgentEnv:
    """Build the environment of a task config; ``horizon`` overrides the task's T."""
    if cfg.kind not in ENVS:
        raise ConfigError(f"unknown task kind {cfg.kind!r}; known: {', '.join(ENVS)}")
    return ENVS[cfg.kind](cfg, horizon)


__all__ = ["ENVS", "EnvState", "FormationEnv", "MultiAgentEnv", "Observation", "Rng", "UnlabeledGoalsEnv", "make_env"]
