"""The stage graph: which commands make the artifacts a baseline needs, and what each of them waits for.

Derived from the baseline registry alone (``baselines.py``), stdlib only. ``neurosym pipeline`` runs a plan in
order; ``benchmarks/run_paper.py`` schedules the same stages over several workers.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from ..baselines import BASELINES, ORACLE, get
from ..config import BaselineConfig

VERBS = ("train", "synth", "retrain", "eval")


@dataclass(frozen=True)
class Stage:
    verb: str  # train, synth, retrain or eval
    baseline: str  # the baseline whose config the command runs with

    @property
    def name(self) -> str:
        return f"{self.verb} {self.baseline}"


def search_baseline(b: BaselineConfig) -> str:
    """The baseline whose `synth` makes the program or tree ``b`` runs under (prog for prog-retrained, ...)."""
    for other in BASELINES.values():
        if other.model == "oracle" and other.comm == b.comm and other.det == b.det:
            return other.name
    raise ValueError(f"no baseline synthesizes what {b.name} needs")


def upstream(name: str) -> list[Stage]:
    """Every stage that makes an artifact baseline ``name`` is evaluated with, in dependency order."""
    b = get(name)
    # the oracle's weights (tf-full, hard-attn, programs, trees, and the start of retraining), or its own model
    need = [Stage("train", b.name if b.model == "own" else ORACLE)]
    if b.comm == "gated":
        need.insert(0, Stage("train", ORACLE))
    if b.comm in ("program", "tree"):
        need.append(Stage("synth", search_baseline(b)))
    if b.model == "retrained":
        need.append(Stage("retrain", b.name))
    return need


def requires(stage: Stage) -> tuple[Stage, ...]:
    """The stages ``stage`` waits for directly."""
    if stage.verb == "train":  # rl starts from the oracle (rl.init=oracle, its default)
        return (Stage("train", ORACLE),) if get(stage.baseline).comm == "gated" else ()
    if stage.verb == "synth":
        return (Stage("train", ORACLE),)
    if stage.verb == "retrain":
        return (Stage("synth", search_baseline(get(stage.baseline))),)
    return tuple(upstream(stage.baseline))


def plan(baselines: Sequence[str]) -> list[Stage]:
    """Every stage the listed baselines need, each once, in dependency order, then their evaluations."""
    out: list[Stage] = []
    for name in baselines:
        out += [s for s in upstream(name) if s not in out]
    return out + [Stage("eval", name) for name in baselines]
