"""Metropolis-Hastings over programs: independent restarts, then a final chain from the best program found.

One code path serves every phase (the reference copies its loop twice). The acceptance is Metropolis with a
temperature relative to the current objective, as the reference's exp(10 (cur - new) / |cur|)
(temperature 0.1).

Two levers shorten the time to a good program without changing the objective (docs/performance.md, section 10):
``patience`` ends a phase whose chain has not improved its own best for that many proposals, and a ``coarse``
scorer (the same objective on a subsample of D) drives the restarts, whose best programs are then scored on the
whole of D before the final chain, which always runs on the whole of D.
"""

from __future__ import annotations

import math
import random
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Callable, Protocol

from ..dsl.ast import And, Or, Rule, Test
from .objective import Score


class Scorer(Protocol):
    def score(self, rules: tuple[Rule, ...]) -> Score: ...

    def accept(self) -> None: ...


def complexity(rules: tuple[Rule, ...]) -> int:
    """Size of a round's rules: one per rule plus one per test in its filter (K .. 3K at filter depth 2)."""
    def tests(c) -> int:
        if isinstance(c, Test):
            return 1
        if isinstance(c, (And, Or)):
            return tests(c.left) + tests(c.right)
        return 0

    return sum(1 + tests(getattr(r, "cond", None)) for r in rules)


@dataclass
class HallOfFame:
    """The best program seen at each complexity (lowest objective) and at each degree level (lowest L1 error,
    level = the degree term rounded up), over every proposal scored on the whole of D (PySR's hall of fame)."""

    by_complexity: dict[int, tuple[Score, tuple[Rule, ...]]] = field(default_factory=dict)
    by_degree: dict[int, tuple[Score, tuple[Rule, ...]]] = field(default_factory=dict)

    def add(self, rules: tuple[Rule, ...], s: Score) -> None:
        c = complexity(rules)
        if c not in self.by_complexity or s.total < self.by_complexity[c][0].total:
            self.by_complexity[c] = (s, rules)
        d = math.ceil(s.degree - 1e-9)
        if d not in self.by_degree or s.l1 < self.by_degree[d][0].l1:
            self.by_degree[d] = (s, rules)

    def front(self, by: str) -> list[tuple[int, Score, tuple[Rule, ...]]]:
        """Non-dominated rows, simplest first: a row is kept only when it beats every simpler (or lower-degree)
        row (on the objective by complexity, on L1 by degree level)."""
        table = self.by_complexity if by == "complexity" else self.by_degree
        key = (lambda s: s.total) if by == "complexity" else (lambda s: s.l1)
        out, best = [], math.inf
        for level in sorted(table):
            s, rules = table[level]
            if key(s) < best - 1e-12:
                out.append((level, s, rules))
                best = key(s)
        return out


@dataclass
class SearchResult:
    best: tuple[Rule, ...]
    best_score: Score
    trace: list[dict] = field(default_factory=list)
    proposed: Counter = field(default_factory=Counter)
    accepted: Counter = field(default_factory=Counter)
    seconds: float = 0.0
    hall: HallOfFame = field(default_factory=HallOfFame)
    stopped: dict[str, int] = field(default_factory=dict)
    """phases ended early by ``patience``: phase name -> proposals it ran"""
    skipped: int = 0
    """programs met again and not scored a second time (the hybrid search's equivalence cache; MCMC: 0)"""

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
    *,
    steps: int,
    restarts: int,
    final_fraction: float,
    temperature: float,
    rng: random.Random,
    on_step: Callable[[int, SearchResult, dict], None] | None = None,
    patience: int = 0,
    coarse: Scorer | None = None,
) -> SearchResult:
    """Run every phase of ``phases``; ``patience`` > 0 ends a phase after that many proposals without a new best of
    its own chain; ``coarse`` (same objective, a subsample of D) scores the restart phases."""
    t0 = time.perf_counter()
    result: SearchResult | None = None
    step = 0
    for phase, n in phases(steps, restarts, final_fraction):
        final = phase == "final" and result is not None
        sc = coarse if (coarse is not None and phase.startswith("restart")) else scorer
        cur = result.best if final else init()  # type: ignore[union-attr]
        cur_score = sc.score(cur)
        sc.accept()
        if result is None:  # the first program, scored on the whole of D (also when restarts run coarse)
            first = cur_score if sc is scorer else scorer.score(cur)
            scorer.accept()
            result = SearchResult(cur, first)
            result.hall.add(cur, first)
        elif sc is scorer:
            if cur_score.total < result.best_score.total:
                result.best, result.best_score = cur, cur_score
            result.hall.add(cur, cur_score)
        chain_best, chain_score, since = cur, cur_score, 0
        for i in range(n):
            cand, move = propose(cur)
            s = sc.score(cand)
            delta = s.total - cur_score.total
            ok = delta <= 0 or rng.random() < math.exp(-delta / (temperature * max(abs(cur_score.total), 1e-9)))
            result.proposed[move] += 1
            if ok:
                sc.accept()
                cur, cur_score = cand, s
                result.accepted[move] += 1
            since += 1
            if s.total < chain_score.total:
                chain_best, chain_score, since = cand, s, 0
            if sc is scorer:
                result.hall.add(cand, s)
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
            if patience and since >= patience and i + 1 < n:
                result.stopped[phase] = i + 1
                break
        if sc is not scorer:  # the restart's best on the whole of D decides what the final chain starts from
            assert result is not None
            full = scorer.score(chain_best)
            scorer.accept()
            result.hall.add(chain_best, full)
            if full.total < result.best_score.total:
                result.best, result.best_score = chain_best, full
    assert result is not None
    result.seconds = time.perf_counter() - t0
    return result
