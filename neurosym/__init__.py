"""neurosym from Python: the command line's verbs as functions (neurosym_cli/api.py) and what a task of your own is
made of (neurosym_cli/tasks). docs/extending.md walks through both.

    import neurosym as ns
    cfg = ns.compose(task="random-grid", budget="tiny")
    ns.train(cfg); program = ns.synth(cfg); ns.retrain(cfg); print(ns.evaluate(cfg, "prog-retrained")["cost"])
"""

from neurosym_cli import __version__
from neurosym_cli.api import compose, evaluate, export, load_program, picks, pipeline, retrain, synth, task, train
from neurosym_cli.config import RunConfig, TaskConfig
from neurosym_cli.dsl import Program, describe, parse, to_text
from neurosym_cli.dsl.vocabulary import Feature, FeatureSet, product_features, vector_features
from neurosym_cli.errors import ConfigError, UserError
from neurosym_cli.tasks import (CAPABILITIES, FeatureMap, FeatureView, Observation, Rng, Scene, Task, TaskState,
                                custom_map, make_task, vector_map)

from . import tasks  # noqa: E402  (neurosym.tasks: the helpers a task module uses)

__all__ = ["CAPABILITIES", "ConfigError", "Feature", "FeatureMap", "FeatureSet", "FeatureView", "Observation",
           "Program", "Rng", "RunConfig", "Scene", "Task", "TaskConfig", "TaskState", "UserError", "__version__",
           "compose", "custom_map", "describe", "evaluate", "export", "load_program", "make_task", "parse", "picks",
           "pipeline", "product_features", "retrain", "synth", "task", "tasks", "to_text", "train", "vector_features",
           "vector_map"]
