"""The hybrid search (synth.search=hybrid, synth/local.py): it finds a planted optimum, never scores a program
twice, fits thresholds without ever getting worse, and is selected by the config (mcmc stays the default)."""

import random

import pytest
import torch

from neurosym_cli.config import ConfigError, SynthConfig
from neurosym_cli.dsl.ast import And, ArgMaxRule, Linear, Or, RandomRule, TrueCond
from neurosym_cli.dsl.ast import Test as Ge  # (not collected as a test class)
from neurosym_cli.dsl.sampling import SearchSpace, grid, neighbours, random_rules
from neurosym_cli.synth.local import Budget, Evaluator, canonical, fit, hybrid
from neurosym_cli.synth.objective import CachedScorer, Score
from neurosym_cli.synth.search import RoundSpec, search_round

SPACE = SearchSpace({f: tuple(round(0.5 * i, 2) for i in range(20)) for f in ("a", "b", "c", "d", "e")}, 2, 2,
                    det=True)
PLANTED = (ArgMaxRule(Linear((("a", 1.0),)), Ge(Linear((("b", -1.0),)), -6.5)),
           ArgMaxRule(Linear((("c", -1.0),)), TrueCond()))


def _test_distance(t, want: Ge) -> float:
    """0 only for ``want``; one per wrong feature or side, plus the grid steps between the thresholds."""
    if isinstance(t, TrueCond):
        return 3.0
    if isinstance(t, (And, Or)):
        return 1.0 + min(_test_distance(t.left, want), _test_distance(t.right, want))
    (name, w), = t.lhs.terms
    (want_name, want_w), = want.lhs.terms
    return (name != want_name) + (w != want_w) + abs(t.threshold - want.threshold) / 0.5


def _distance(rules) -> float:
    """A synthetic objective with its only optimum (0) at PLANTED: structural distance, rule by rule."""
    total = 0.0
    for r, want in zip(rules, PLANTED):
        if not isinstance(r, ArgMaxRule):
            total += 4.0
            continue
        total += (r.score.terms[0][0] != want.score.terms[0][0]) + (r.score.terms[0][1] != want.score.terms[0][1])
        if isinstance(want.cond, TrueCond):
            total += 0.0 if isinstance(r.cond, TrueCond) else 2.0
        else:
            total += _test_distance(r.cond, want.cond)
    return total


class Synthetic:
    """A scorer of the mcmc.Scorer protocol over the synthetic objective, counting every program it scores."""

    def __init__(self):
        self.scored: list = []

    def score(self, rules) -> Score:
        self.scored.append(canonical(rules))
        d = _distance(rules)
        return Score(d, d, 0.0)

    def accept(self) -> None:
        pass


def _first_zero(scores) -> int | None:
    return next((i + 1 for i, s in enumerate(scores) if s < 1e-9), None)


def test_planted_program_is_the_synthetic_optimum():
    assert _distance(PLANTED) == 0.0
    assert all(_distance(random_rules(SPACE, random.Random(s))) > 0 for s in range(50))


def test_hybrid_finds_the_planted_optimum_faster_than_random_proposals():
    budget = 3000
    for seed in range(3):
        sc = Synthetic()
        rng = random.Random(seed)
        res = hybrid(lambda: random_rules(SPACE, rng), SPACE, sc, steps=budget, restarts=2, final_fraction=0.2,
                     rng=rng)
        assert res.best_score.total < 1e-9, res.best
        hit = _first_zero([row["objective"] for row in res.trace])
        rng = random.Random(seed)
        blind = _first_zero([_distance(random_rules(SPACE, rng)) for _ in range(budget)])
        assert hit is not None and (blind is None or hit < blind), (hit, blind)
        assert hit < budget // 2


def test_equivalence_cache_never_scores_a_program_twice():
    sc = Synthetic()
    rng = random.Random(0)
    res = hybrid(lambda: random_rules(SPACE, rng), SPACE, sc, steps=1500, restarts=3, final_fraction=0.2, rng=rng)
    assert len(sc.scored) == len(set(sc.scored)) == sum(res.proposed.values()) <= 1500
    assert res.skipped > 0  # programs were met again (climbing back, fitting over the same grid) and not rescored
    # programs that differ only in the order of an and/or's operands are one program
    t1, t2 = Ge(Linear((("a", 1.0),)), 1.0), Ge(Linear((("b", 1.0),)), 2.0)
    a = (RandomRule(And(t1, t2)),)
    assert canonical(a) == canonical((RandomRule(And(t2, t1)),)) != canonical((RandomRule(Or(t1, t2)),))


def test_neighbours_are_single_edits_on_the_grid():
    rules = (ArgMaxRule(Linear((("a", 1.0),)), And(Ge(Linear((("b", -1.0),)), -3.0), Ge(Linear((("c", 1.0),)),
                                                                                         2.5))),
             RandomRule(TrueCond()))
    space = SearchSpace(SPACE.quantiles, 2, 2)
    near = neighbours(rules, space)
    assert len({n for n, _ in near}) == len(near) and rules not in {n for n, _ in near}
    for new, move in near:
        assert sum(x != y for x, y in zip(new, rules)) == 1
    thresholds = {new[0].cond.left.threshold for new, move in near if move == "threshold"
                  and isinstance(new[0].cond, And) and new[0].cond.right == rules[0].cond.right}
    # for -b (grid -9.5 .. 0 by 0.5): the values next to -3.0, an eighth of the grid away (2 values), the ends
    assert thresholds == {-3.5, -2.5, -4.0, -2.0, -9.5, 0.0}
    assert grid(space, "b", -1.0)[0] == -9.5 and grid(space, "b", 1.0)[-1] == 9.5


def _real_scorer():
    from test_synth import _setup

    env, pol, data = _setup(rollouts=3)
    sc = CachedScorer(pol, env, data, round_idx=0, version="v1", lam=0.5, objective="paper", cap=2, samples=1,
                      gen=torch.Generator().manual_seed(1), device=torch.device("cpu"))
    from neurosym_cli.synth.search import feature_quantiles

    return sc, SearchSpace(feature_quantiles(sc, torch.Generator().manual_seed(0)), 2, 2)


def test_threshold_fitting_never_makes_the_objective_worse():
    sc, space = _real_scorer()
    rng = random.Random(0)
    improved = 0
    for _ in range(6):
        rules = random_rules(space, rng)
        ev = Evaluator(sc, on_step=None, max_lookups=10**6)
        ev.budget = Budget(10**6, float("inf"))
        s = ev.score(rules, "init", "test")
        ev.stand(rules, s)
        fitted, f = fit(rules, s, space=space, ev=ev, phase="test")
        assert f.total <= s.total
        improved += f.total < s.total
        again = sc.score(fitted)  # the fitted program's score is its own (not a stale incremental one)
        assert abs(again.total - f.total) <= 1e-4 * max(1.0, f.total)
    assert improved >= 1


def test_search_option_selects_the_hybrid_which_is_the_default_and_mcmc_stays_selectable():
    # issue 37: the config's default is the hybrid search; a RoundSpec made by hand (the paper's code path) keeps MCMC
    assert SynthConfig().search == "hybrid" and SynthConfig(search="mcmc").search == "mcmc"
    assert RoundSpec(steps=1, restarts=0, final_fraction=0.0, temperature=0.1, rules=1, max_depth=2,
                     det=False).search == "mcmc"
    with pytest.raises(ConfigError, match="synth.search"):
        SynthConfig(search="anneal")
    sc, _ = _real_scorer()
    spec = RoundSpec(steps=60, restarts=1, final_fraction=0.2, temperature=0.1, rules=2, max_depth=2, det=False,
                     search="hybrid")
    res = search_round(sc, spec, "0/0/t", torch.Generator().manual_seed(0))
    assert 0 < sum(res.proposed.values()) <= 60 and "init" in res.proposed
    assert res.trace[-1]["best"] == res.best_score.total == min(row["objective"] for row in res.trace)
