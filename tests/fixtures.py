"""Small shared fixtures of the test modules (imported as `from fixtures import ...`)."""

from __future__ import annotations


def feature_map(kind: str = "formation", version: str = "v1", goals: int = 10):
    """The feature map of a paper task: formation (random-cross's goal vector) or unlabeled (position, goals)."""
    if kind == "formation":
        from neurosym_cli.tasks.random_cross import CrossConfig, RandomCrossTask

        return RandomCrossTask(CrossConfig(name="random-cross")).features(version)
    from neurosym_cli.tasks.unlabeled_goals import UnlabeledConfig, UnlabeledGoalsTask

    return UnlabeledGoalsTask(UnlabeledConfig(name="unlabeled-goals", agents_per_group=goals)).features(version)
