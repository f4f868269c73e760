"""The hybrid program search (``synth.search=hybrid``): restarts of local search instead of Metropolis chains.

Each phase of ``mcmc.phases`` (restarts from random programs, then a final phase from the best program found)
runs iterated local search:

- **hill climbing**: first improvement over every single-edit neighbour of the current program
  (``sampling.neighbours``: a threshold to the next quantile of its feature, a feature swapped, a side flipped, a
  clause dropped or added, an argmax score's feature or sign, a rule's kind), in a random order;
- **fitting**: at each local optimum, coordinate search over every test's side and threshold on the quantile grid
  (coarse, then the grid values around the best), keeping a value only when it is strictly better;
- **kicks** (last phase only; a restart ends at its local optimum and leaves the rest of its share to the
  phases after it): from the best program, two to four random MCMC moves (``sampling.propose``), then climbing
  and fitting again; the search keeps the better of the two.

An equivalence cache keyed by the canonical program (and/or operands in a fixed order) remembers every score, so
no program is scored twice. The budget is the same as MCMC's: ``steps`` scored programs (cache hits are free),
and optionally a wall-clock limit. Every scored program is one row of the trace, with MCMC's columns.
"""

from __future__ import annotations

import random
import time
from dataclasses import dataclass, replace
from typing import Callable

from ..dsl.ast import And, ArgMaxRule, Cond, Linear, Or, Rule, Test
from ..dsl.sampling import SearchSpace, grid, neighbours, propose, test_at, test_sites, with_test
from .mcmc import Scorer, SearchResult, phases
from .objective import Score

EPS = 1e-12
"""an improvement smaller than this is no improvement (float noise of incremental sums)"""


def canonical(rules: tuple[Rule, ...]) -> tuple[Rule, ...]:
    """The program with every and/or's operands in a fixed order: equal for programs that decide alike by form.
    Rule order is kept (a random rule's draws depend on its position)."""
    def cond(c: Cond) -> Cond:
        if isinstance(c, (And, Or)):
            a, b = sorted((cond(c.left), cond(c.right)), key=repr)
            return type(c)(a, b)
        return c

    return tuple(replace(r, cond=cond(r.cond)) for r in rules)


class OutOfBudget(Exception):
    """The search's evaluations or seconds (or the phase's share of them) are spent."""


@dataclass
class Budget:
    """Where a phase must stop: the evaluation count and the clock time (perf_counter seconds; inf: none)."""

    evaluations: int
    deadline: float


class Evaluator:
    """Scores each program once (the equivalence cache), spends the budget, and records the trace, the hall of
    fame and the best program in a ``SearchResult`` as ``mcmc.metropolis`` does."""

    def __init__(self, scorer: Scorer, *, on_step: Callable | None, max_lookups: int):
        self.scorer, self.on_step, self.max_lookups = scorer, on_step, max_lookups
        self.seen: dict[tuple[Rule, ...], Score] = {}
        self.evaluations, self.lookups = 0, 0
        self.last: tuple[Rule, ...] | None = None  # the canonical form of the program the scorer scored last
        self.result: SearchResult | None = None
        self.budget = Budget(0, float("inf"))
        self.t0 = time.perf_counter()
        self.current: Score | None = None  # the program the search stands on (the trace's 'current')

    def score(self, rules: tuple[Rule, ...], move: str, phase: str) -> Score:
        """The objective of ``rules``, from the cache or the scorer; raises OutOfBudget when spent."""
        key = canonical(rules)
        self.lookups += 1
        if key in self.seen:
            if self.lookups > self.max_lookups:  # only known programs left to visit: nothing more to learn
                raise OutOfBudget
            return self.seen[key]
        if self.evaluations >= self.budget.evaluations or time.perf_counter() >= self.budget.deadline:
            raise OutOfBudget
        s = self.scorer.score(rules)
        self.seen[key], self.last = s, key
        self.evaluations += 1
        res = self.result
        if res is None:
            res = self.result = SearchResult(rules, s)
        elif s.total < res.best_score.total:
            res.best, res.best_score = rules, s
        res.hall.add(rules, s)
        res.proposed[move] += 1
        cur = self.current or s
        row = {"step": self.evaluations, "phase": phase, "move": move, "accepted": int(s.total < cur.total - EPS),
               "objective": s.total, "current": cur.total, "best": res.best_score.total,
               "best_l1": res.best_score.l1, "best_degree": res.best_score.degree}
        res.trace.append(row)
        res.seconds = time.perf_counter() - self.t0
        if self.on_step is not None:
            self.on_step(self.evaluations, res, row)
        return s

    def stand(self, rules: tuple[Rule, ...], s: Score, move: str | None = None) -> None:
        """Move the search onto ``rules``: the base of incremental scoring when the scorer scored it last."""
        self.current = s
        if self.last == canonical(rules):
            self.scorer.accept()
        if move is not None and self.result is not None:
            self.result.accepted[move] += 1


def climb(rules: tuple[Rule, ...], s: Score, *, space: SearchSpace, ev: Evaluator, rng: random.Random,
          phase: str) -> tuple[tuple[Rule, ...], Score]:
    """First-improvement hill climbing over ``sampling.neighbours`` until no neighbour is strictly better."""
    while True:
        near = neighbours(rules, space)
        rng.shuffle(near)
        for cand, move in near:
            c = ev.score(cand, move, phase)
            if c.total < s.total - EPS:
                rules, s = cand, c
                ev.stand(rules, s, move)
                break
        else:
            return rules, s


def fit(rules: tuple[Rule, ...], s: Score, *, space: SearchSpace, ev: Evaluator, phase: str,
        passes: int = 2) -> tuple[tuple[Rule, ...], Score]:
    """Coordinate search over each test's side and threshold on the quantile grid (every ``stride``-th value, then
    the values around the best) and each argmax score's sign. A coordinate changes only to a strictly better
    value, so the objective never gets worse."""
    for _ in range(passes):
        before = s.total
        for site in test_sites(rules):
            t = test_at(rules, site)
            (name, _), = t.lhs.terms
            for sign in (1.0, -1.0):
                g = grid(space, name, sign)
                stride = max(1, len(g) // 12)
                coarse = list(range(0, len(g), stride))
                for idx in (coarse, None):  # None: the fine values next to the best coarse one
                    if idx is None:
                        now = test_at(rules, site)
                        if now.lhs.terms[0][1] != sign or stride == 1:  # the best is on the other side
                            continue
                        at = min(range(len(g)), key=lambda i: abs(g[i] - now.threshold))
                        idx = [i for i in range(at - stride + 1, at + stride) if 0 <= i < len(g)]
                    for i in idx:
                        cand = with_test(rules, site, Test(Linear(((name, sign),)), g[i]))
                        if cand == rules:
                            continue
                        c = ev.score(cand, "fit", phase)
                        if c.total < s.total - EPS:
                            rules, s = cand, c
                            ev.stand(rules, s, "fit")
        for k, r in enumerate(rules):
            if isinstance(r, ArgMaxRule):
                (name, w), = r.score.terms
                cand = rules[:k] + (replace(r, score=Linear(((name, -w),))),) + rules[k + 1:]
                c = ev.score(cand, "fit", phase)
                if c.total < s.total - EPS:
                    rules, s = cand, c
                    ev.stand(rules, s, "fit")
        if s.total >= before - EPS:
            break
    return rules, s


def descend(rules: tuple[Rule, ...], s: Score, *, space: SearchSpace, ev: Evaluator, rng: random.Random,
            phase: str) -> tuple[tuple[Rule, ...], Score]:
    """Climb and fit in turn until fitting finds nothing better: a local optimum of both."""
    while True:
        rules, s = climb(rules, s, space=space, ev=ev, rng=rng, phase=phase)
        fitted, f = fit(rules, s, space=space, ev=ev, phase=phase)
        if f.total >= s.total - EPS:
            return rules, s
        rules, s = fitted, f


def hybrid(init: Callable[[], tuple[Rule, ...]], space: SearchSpace, scorer: Scorer, *, steps: int, restarts: int,
           final_fraction: float, rng: random.Random, seconds: float = 0.0,
           on_step: Callable[[int, SearchResult, dict], None] | None = None) -> SearchResult:
    """Iterated local search in the phases of ``mcmc.phases(steps, restarts, final_fraction)``: each restart from a
    random program, the final phase from the best; ``steps`` scored programs in all, and when ``seconds`` > 0 at
    most that wall time, shared among the phases as the steps are."""
    ev = Evaluator(scorer, on_step=on_step, max_lookups=50 * steps + 1000)
    t0 = ev.t0
    done = 0
    schedule = phases(steps, restarts, final_fraction)
    for i, (phase, n) in enumerate(schedule):
        done += n
        ev.budget = Budget(done, t0 + seconds * done / steps if seconds > 0 else float("inf"))
        try:
            if phase == "final" and ev.result is not None:
                start = ev.result.best
            else:
                start = init()
            s = ev.score(start, "init", phase)
            ev.stand(start, s)
            best, best_s = descend(start, s, space=space, ev=ev, rng=rng, phase=phase)
            if i + 1 < len(schedule):
                continue  # a restart ends at its local optimum: what it leaves goes to the next phases
            while True:  # kicks from the best until the budget is spent
                kicked = best
                for _ in range(rng.randint(2, 4)):
                    kicked, _ = propose(kicked, space, rng)
                k = ev.score(kicked, "kick", phase)
                ev.stand(kicked, k)
                cand, c = descend(kicked, k, space=space, ev=ev, rng=rng, phase=phase)
                if c.total < best_s.total - EPS:
                    best, best_s = cand, c
        except OutOfBudget:
            pass
    res = ev.result
    if res is None:  # no budget at all: the first program, scored anyway
        first = init()
        res = SearchResult(first, scorer.score(first))
        scorer.accept()
    res.seconds = time.perf_counter() - t0
    res.skipped = ev.lookups - ev.evaluations
    return res
