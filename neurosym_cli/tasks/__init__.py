"""Tasks: the multi-agent problems neurosym trains, searches and evaluates on, behind one small protocol.

    base.py              the protocol (Task, TaskState, Observation, Scene, Rng), capabilities, shape letters
    features.py          feature maps: a task's declared features and how each is computed (section 3.2)
    registry.py          tasks by import path (``_target_`` in a task YAML), search path, entry points, checks
    planar.py            what the paper's tasks share: agents in the plane, noisy relative observations
    formation.py         formation flying: schema, state, dynamics, cost, collisions (random-cross, random-grid)
    random_cross.py      random-cross (paper section 4)
    two_groups_cross.py  two-groups-cross (paper Figure 1)
    random_grid.py       random-grid (paper section 4)
    unlabeled_goals.py   unlabeled-goals (paper section 4, two communication rounds)

The paper's tasks use the same mechanism as a user's (docs/extending.md): a YAML in a config directory naming the
class, the class naming its schema. Nothing here is special about them.
"""

from __future__ import annotations

from .base import CAPABILITIES, Observation, Rng, Scene, Task, TaskState, require
from .features import FeatureMap, FeatureView, custom_map, vector_map
from .registry import make_task, probe, task_class, typed_task

__all__ = ["CAPABILITIES", "FeatureMap", "FeatureView", "Observation", "Rng", "Scene", "Task", "TaskState",
           "custom_map", "make_task", "probe", "require", "task_class", "typed_task", "vector_map"]
