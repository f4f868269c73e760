"""The degree-budget front (``synth.front=true``): for each budget b of the degree (max in+out on D, mean over its
states), the lowest-L1 program found whose degree is within b, from b = 0 (silence) up to what K rules reach.

Cheap by construction: every program the single-lam search scored on the whole of D is already archived by degree
level (``mcmc.HallOfFame.by_degree``, the lowest L1 per level); each budget then runs a short constrained chain,
L1 / L1(silence) + PENALTY * relu(degree - b), started from the best archived program within b, and every program
those chains score joins the pool. A budget's row is the lowest-L1 program of the pool within it, so the front is
monotone: a larger budget may take any smaller budget's program (it is within the larger budget too).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import torch

from ..dsl.ast import And, ArgMaxRule, Linear, Program, RandomRule, Rule, Test
from ..dsl.printer import to_text
from .objective import CachedScorer, Score
from .search import RoundSpec, search_round

PENALTY = 100.0
"""the constrained objective's price of one unit of degree above the budget, in units of silence's L1: any excess
costs more than silence's whole action gap, so a chain never settles above its budget"""
TOL = 1e-9
"""a degree within TOL of the budget is within it (the degree is a mean of integers)"""


def default_budgets(k: int, n_max: int) -> list[float]:
    """0 (silence), 1, ..., min(K + N - 1, 3K): K + N - 1 is the most K rules can reach (hear K, be heard by all
    N - 1 others); 3K bounds the search where N is large (a K-rule program's degree beyond 3K means one agent is a
    hub, which the front need not map step by step)."""
    return [float(b) for b in range(min(k + n_max - 1, 3 * k) + 1)]


def silence(feature: str, k: int, det: bool = False) -> tuple[Rule, ...]:
    """K rules that never fire: random(filter(f >= 1 and f <= 0, l)) asks for both at once; ``det`` (det-prog's
    space, argmax rules only): argmax(map(1.0*f, filter(...))), so a chain started from it stays in that space."""
    never = And(Test(Linear(((feature, 1.0),)), 1.0), Test(Linear(((feature, -1.0),)), -0.0))
    return ((ArgMaxRule(Linear(((feature, 1.0),)), never) if det else RandomRule(never)),) * k


RANGE_FEATURE = "d"
"""the other agent's distance (o_ij's first two columns' norm, tasks/features.vector_map's convention)"""
RANGE_BUDGETS = (1.0, 2.0, 3.0)
"""the sparse end of the front, where it also offers 'ask the nearest agent within r' (``range_rows``)"""


def nearest_within(radius: float) -> tuple[Rule, ...]:
    """argmax(map(-1.0*d, filter(d <= radius, l))): ask the nearest agent at most ``radius`` away (the paper's
    dist with a range), one rule."""
    near = Linear(((RANGE_FEATURE, -1.0),))
    return (ArgMaxRule(near, Test(near, -radius)),)


def nearest_radii(scorer: CachedScorer, n_q: int = 49) -> tuple[float, ...]:
    """The radii the sparse end tries: quantiles 2 %..98 % of every agent's distance to its nearest other agent over
    D's states, rounded to 2 digits (at r, about that share of the agents has someone within r). The nearest
    distance, not every pair's: in a large team (the swarm, N = 200) even the 2 % quantile of all pairs' distances
    holds several agents around each, past every budget of the sparse end."""
    if RANGE_FEATURE not in scorer.data[0].feats.names:
        return ()
    near = []
    for d in scorer.data:
        v = d.feats[RANGE_FEATURE].expand(d.s, d.n, d.n).float()
        self_pair = torch.eye(d.n, dtype=torch.bool, device=v.device).expand(d.s, -1, -1)
        near.append(v.masked_fill(self_pair, float("inf")).amin(-1).flatten().cpu())  # (S N,)
    x = torch.cat(near)
    x = x[torch.isfinite(x)]
    if x.numel() == 0:
        return ()
    q = torch.quantile(x[:1_000_000], torch.linspace(0.02, 0.98, n_q))  # torch.quantile's input has a size limit
    return tuple(sorted({round(float(r), 2) + 0.0 for r in q}))


def range_rows(scorer: CachedScorer, radii: tuple[float, ...], budgets: list[float], unit: float) -> list[dict]:
    """Per budget of RANGE_BUDGETS within ``budgets``: the nearest-within-r program of the largest r of ``radii``
    (``nearest_radii``: the nearest-agent distance's quantile grid on D) whose max in+out on D is within it; rows
    as ``search_front``'s, with ``radius``. Why: at the sparse end the front's lowest-L1 programs imitate the oracle hearing everybody, and an
    oracle hearing one agent imitates it badly whatever it hears, so L1 ranks them by little; a nearest-within-r
    program ranks low on L1 yet, retrained, can close the whole gap (docs/fidelity.md, 'Degree-budget front').
    Empty when the task has no distance feature."""
    if RANGE_FEATURE not in scorer.data[0].feats.names:
        return []
    entries = [(r, _entry(scorer, nearest_within(r), "range")) for r in sorted(r for r in radii if r > 0)]
    rows = []
    for b in (b for b in RANGE_BUDGETS if b <= max(budgets) + TOL):
        ok = [(r, e) for r, e in entries if e.degree <= b + TOL]
        if ok:
            r, e = ok[-1]
            rows.append({**_row(b, e, unit), "radius": r})
    return rows


def leaves_space(rec: dict, det: bool) -> bool:
    """Whether a front.json's programs leave the space their search allows: a random rule in det-prog's (argmax
    rules only). Fronts of det-prog searched before 2026-12-05 did: their chains started from a random silence."""
    from ..dsl.parser import parse

    if not det:
        return False
    rows = [row for r in rec.get("rounds", []) for key in ("budgets", "range") for row in r.get(key, [])]
    return any(isinstance(rule, RandomRule) for row in rows for rnd in parse(row["program"] + "\n").rounds
               for rule in rnd)


class BudgetScorer:
    """The constrained objective of one budget, over a round's scorer: L1 / L1(silence) + PENALTY * relu(degree -
    budget); ``Score.l1`` and ``Score.degree`` stay the scorer's (action units, max in+out)."""

    def __init__(self, scorer: CachedScorer, budget: float, unit: float):
        self.scorer, self.budget, self.unit = scorer, budget, unit
        self.fmap, self.data = scorer.fmap, scorer.data  # what search_round reads to build the search space

    def score(self, rules: tuple[Rule, ...]) -> Score:
        s = self.scorer.score(rules)
        return Score(s.l1 / self.unit + PENALTY * max(0.0, s.degree - self.budget), s.l1, s.degree)

    def accept(self) -> None:
        self.scorer.accept()


@dataclass(frozen=True)
class Entry:
    """One program of the pool, scored by the front's scorer (degree: max in+out, whatever the search's objective)."""

    rules: tuple[Rule, ...]
    l1: float
    degree: float
    max_in: float
    max_out: float
    source: str  # silence, search (the single-lam search's archive), budget<b> (that budget's constrained chain)


def _entry(scorer: CachedScorer, rules: tuple[Rule, ...], source: str) -> Entry:
    s = scorer.score(rules)
    stats = scorer.degree_stats()
    return Entry(rules, s.l1, s.degree, stats["max_in"], stats["max_out"], source)


def _row(budget: float, e: Entry, unit: float) -> dict:
    """One row of the front (front.json): the budget and its program's L1, L1 share of silence's, degrees, text."""
    return {"budget": budget, "l1": e.l1, "l1_ratio": e.l1 / unit, "degree": e.degree, "max_in": e.max_in,
            "max_out": e.max_out, "program": to_text(Program((e.rules,))).strip(), "source": e.source}


def best_within(pool: list[Entry], budget: float) -> Entry | None:
    """The lowest-L1 entry whose degree is within ``budget`` (ties: the lower degree, then the earlier entry)."""
    ok = [e for e in pool if e.degree <= budget + TOL]
    return min(ok, key=lambda e: (e.l1, e.degree)) if ok else None


def search_front(scorer: CachedScorer, spec: RoundSpec, *, archive: list[tuple[Rule, ...]], budgets: list[float],
                 steps: int, seed: str, gen: torch.Generator) -> tuple[list[dict], list[dict]]:
    """One row per budget, ascending: {budget, l1, l1_ratio, degree, max_in, max_out, program, source}; and the
    sparse end's nearest-within-r rows (``range_rows``).

    ``scorer`` must count max in+out (objective paper or scaled); ``archive``: programs the single-lam search found
    (its hall of fame by degree level); ``steps``: proposals of each budget's constrained chain; ``seed``: the
    chains' draws (each budget its own), so the front never moves the single-lam search that ran before it."""
    assert not scorer.form.hinge, "the front counts max in+out: give it a paper or scaled scorer"
    unit = scorer.silent_l1()
    if not unit > 0:
        unit = 1.0  # the oracle ignores its messages: every program ties with silence, L1 ratios read as L1
    pool = [_entry(scorer, silence(scorer.data[0].feats.names[0], spec.rules, spec.det), "silence")]
    pool += [_entry(scorer, rules, "search") for rules in archive]
    chain = dataclasses.replace(spec, steps=steps, restarts=0, patience=0, search="mcmc")
    for b in sorted(budgets):
        start = best_within(pool, b)
        if b <= TOL or steps == 0 or start is None:
            continue  # budget 0 admits silence alone: nothing to search
        res = search_round(BudgetScorer(scorer, b, unit), chain, f"{seed}/budget{b:g}", gen,  # type: ignore[arg-type]
                           start=start.rules)
        found = {rules for _, rules in res.hall.by_degree.values()} | {res.best}
        pool += [_entry(scorer, rules, f"budget{b:g}") for rules in found]
    rows = []
    for b in sorted(budgets):
        e = best_within(pool, b)
        assert e is not None  # silence (degree 0) is within every budget
        rows.append(_row(b, e, unit))
    return rows, range_rows(scorer, nearest_radii(scorer), budgets, unit)
