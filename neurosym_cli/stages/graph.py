"""The stage graph: which commands make the artifacts a baseline needs, and what each of them waits for.

Asked of the schemes alone (``schemes.SCHEMES``: each answers its upstream stages and what its own stages wait
for), stdlib only. ``neurosym pipeline`` runs a plan's stages as their waits allow, pipeline.jobs at once
(stages/flow.py); ``benchmarks/run_paper.py`` schedules the stages of several tasks over its workers.
"""

from __future__ import annotations

from typing import Sequence

from ..baselines import VERBS, Stage
from ..schemes import get

__all__ = ["Stage", "VERBS", "plan", "requires", "upstream"]


def upstream(name: str) -> list[Stage]:
    """Every stage that makes an artifact baseline ``name`` is evaluated with, in dependency order."""
    return get(name).upstream()


def requires(stage: Stage) -> tuple[Stage, ...]:
    """The stages ``stage`` waits for directly."""
    if stage.verb == "eval":
        return tuple(upstream(stage.baseline))
    return get(stage.baseline).requires(stage.verb)


def plan(baselines: Sequence[str]) -> list[Stage]:
    """Every stage the listed baselines need, each once, in dependency order, then their evaluations."""
    out: list[Stage] = []
    for name in baselines:
        out += [s for s in upstream(name) if s not in out]
    return out + [Stage("eval", name) for name in baselines]
