"""What a task module imports: the protocol's types and the small tensor helpers the paper's tasks use."""

from neurosym_cli.tasks.base import (CAPABILITIES, Observation, Rng, Scene, Task, TaskState, clip_speed, concat_states,
                                     eye_mask, pairwise_distances, require, safe_norm)
from neurosym_cli.tasks.features import Columns, FeatureMap, FeatureView, column_feature, custom_map, vector_map
from neurosym_cli.tasks.planar import PlanarConfig, collision_count, relative_observation

__all__ = ["CAPABILITIES", "Columns", "column_feature", "FeatureMap", "FeatureView", "Observation", "PlanarConfig", "Rng", "Scene", "Task",
           "TaskState", "clip_speed", "collision_count", "concat_states", "custom_map", "eye_mask",
           "pairwise_distances", "relative_observation", "require", "safe_norm", "vector_map"]
