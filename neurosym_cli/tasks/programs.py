"""A run's task and a program against it: the task's feature map, and the check that a program reads only its
features. No torch at import (show-program reads a program without it)."""

from __future__ import annotations

from ..config import ConfigError, RunConfig
from ..dsl.ast import Program
from .features import FeatureMap


def task_of(cfg: RunConfig, task=None):
    """``task``, or the task of ``cfg`` built from its config when not given."""
    from .registry import make_task

    return task if task is not None else make_task(cfg.task, cfg.horizon)


def feature_map(cfg: RunConfig, task=None) -> FeatureMap:
    """The feature map ``cfg.features`` of the task (built from the config when not given)."""
    return task_of(cfg, task).features(cfg.features)


def check_program(program: Program, cfg: RunConfig, source: str, fmap: FeatureMap | None = None) -> None:
    """A program runs on this task only with its number of rounds and features of this task's feature map."""
    if program.n_rounds != cfg.task.rounds:
        raise ConfigError(f"{source}: the program has {program.n_rounds} round(s), task {cfg.task.name} "
                          f"{cfg.task.rounds}")
    known = (fmap or feature_map(cfg)).vocab
    unknown = known.unknown(program.features())
    if unknown:
        raise ConfigError(f"{source}: feature(s) {', '.join(unknown)} not in task {cfg.task.name} with "
                          f"features={cfg.features}; it has: {', '.join(known.names)}")
