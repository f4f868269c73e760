"""Metropolis-Hastings over programs: independent restarts, then a final chain from the best program found.

One code path serves every phase (the reference copies its loop twice). The acceptance is Metropolis with a
temperature relative to the current objective, as the reference's exp(10 (cur - new) / |cur|)
(temperature 0.1).
"""

from __future__ import annotations

import math
import random
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Callable, Protocol

from ..dsl.ast import Rule
from .objective import Score


class Scorer(Protocol):
    def score(self, rules: tuple[Rule, ...]) -> Score: ...

    def accept(self) -> None: ...


@dataclass
class SearchResult:
    best: tuple[Rule, ...]
    best_score: Score
    trace: list[dict] = field(default_factory=list)
    proposed: Counter = field(default_factory=Counter)
    accepted: Counter = field(default_factory=Counter)
    seconds: float = 0.0

    @property
    def proposals_per_second(self) -> float:
        return sum(self.proposed.values()) / max(self.seconds, 1e-9)

    def acceptance(self) -> dict[str, float]:
        return {m: self.accepted[m] / n for m, n in sorted(self.proposed.items()) if n}


def phases(steps: int, restarts: int, final_fraction: float) -> list[tuple[str, int]]:
    """[(phase name, steps)]: `restarts` chains from random programs, then the final chain from the best."""
    if restarts == 0:
        return [("chain", steps)]
    final = int(round(steps * final_fraction))
    each, extra = divmod(steps - final, restarts)
    out = [(f"restart{k + 1}", each + (1 if k < extra else 0)) for k in range(restarts)]
    return out + ([("final", final)] if final else [])


def metropolis(
    init: Callable[[], tuple[Rule, ...]],
    propose: Callable[[tuple[Rule, ...]], tuple[tuple[Rule, ...], str]],
    scorer: Scorer,
    steps: int,
    restarts: int,
    final_fraction: float,
    temperature: float,
    rng: random.Random,
    on_step: Callable[[int, SearchResult, dict], None] | None = None,
) -> SearchResult:
    t0 = time.perf_counter()
    result: SearchResult | None = None
    step = 0
    for phase, n in phases(steps, restarts, final_fraction):
        cur = result.best if (phase == "final" and result is not None) else init()
        cur_score = scorer.score(cur)
        scorer.accept()
        if result is None:
            result = SearchResult(cur, cur_score)
        elif cur_score.total < result.best_score.total:
            result.best, result.best_score = cur, cur_score
        for _ in range(n):
            cand, move = propose(cur)
            s = scorer.score(cand)
            delta = s.total - cur_score.total
            ok = delta <= 0 or rng.random() < math.exp(-delta / (temperature * max(abs(cur_score.total), 1e-9)))
            result.proposed[move] += 1
            if ok:
                scorer.accept()
                cur, cur_score = cand, s
                result.accepted[move] += 1
            if s.total < result.best_score.total:
                result.best, result.best_score = cand, s
            step += 1
            row = {"step": step, "phase": phase, "move": move, "accepted": int(ok), "objective": s.total,
                   "current": cur_score.total, "best": result.best_score.total, "best_l1": result.best_score.l1,
                   "best_degree": result.best_score.degree}
            result.trace.append(row)
            result.seconds = time.perf_counter() - t0
            if on_step is not None:
                on_step(step, result, row)
    assert result is not None
    result.seconds = time.perf_counter() - t0
    return result
