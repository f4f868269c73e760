"""Random programs and the MCMC neighbourhood over the grammar (paper section 3.4: 'standard neighbour programs').

Tests and scores use one feature with weight +-1, so programs read like the paper's
(``theta >= -1.85``, ``argmax(map(-1.0*d, ...))``); thresholds are drawn from the feature's empirical quantiles
and moved on a 0.01 grid, in world units. All randomness comes from a ``random.Random`` owned by the caller.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, replace
from functools import lru_cache

from .ast import And, ArgMaxRule, Cond, Linear, Or, RandomRule, Rule, Test, TrueCond

MOVES = ("threshold", "feature", "sign", "shape", "kind", "rule")
_MOVE_WEIGHTS = (0.35, 0.15, 0.1, 0.15, 0.1, 0.15)
MOVE_HELP = {
    "threshold": "nudge one filter threshold",
    "feature": "swap the feature of a filter test or argmax score",
    "sign": "flip a test's side (f >= c to -f >= -c) or a score's sign",
    "shape": "add, drop or and/or-toggle a filter clause",
    "kind": "turn random into argmax or back",
    "rule": "replace one rule by a fresh random one",
}
"""what each MCMC move changes, for the live view and `neurosym synth --help`"""


@dataclass(frozen=True)
class SearchSpace:
    """What proposals may use: features with their value quantiles (world units), K, depth, rule kinds."""

    quantiles: dict[str, tuple[float, ...]]  # feature name -> sorted quantiles of its values on the dataset
    rules: int  # K
    max_depth: int = 2
    det: bool = False  # argmax rules only (det-prog)
    own_scores: bool = True  # argmax scores may read the asking agent's own state (they tie every candidate)
    own: frozenset[str] = frozenset()  # the features of the asking agent's own state (FeatureSet.agent_level)

    @property
    def features(self) -> list[str]:
        return sorted(self.quantiles)

    @property
    def score_features(self) -> list[str]:
        """Features an argmax score may read: all, or (own_scores=False) those that vary with the candidate."""
        return [f for f in self.features if self.own_scores or f not in self.own]

    def spread(self, name: str) -> float:
        q = self.quantiles[name]
        return max(q[-1] - q[0], 1e-3)


def _r2(x: float) -> float:
    return round(x, 2) + 0.0  # + 0.0 turns -0.0 into 0.0


def random_test(space: SearchSpace, rng: random.Random, feature: str | None = None) -> Test:
    f = feature or rng.choice(space.features)
    sign = rng.choice((1.0, -1.0))
    q = rng.choice(space.quantiles[f])
    return Test(Linear(((f, sign),)), _r2(sign * q))


def random_cond(space: SearchSpace, rng: random.Random) -> Cond:
    u = rng.random()
    if u < 0.15:
        return TrueCond()
    if space.max_depth < 2 or u < 0.7:
        return random_test(space, rng)
    op = And if u < 0.85 else Or
    return op(random_test(space, rng), random_test(space, rng))


def random_score(space: SearchSpace, rng: random.Random) -> Linear:
    return Linear(((rng.choice(space.score_features), rng.choice((1.0, -1.0))),))


def random_rule(space: SearchSpace, rng: random.Random) -> Rule:
    if space.det or rng.random() < 0.5:
        return ArgMaxRule(random_score(space, rng), random_cond(space, rng))
    return RandomRule(random_cond(space, rng))


def random_rules(space: SearchSpace, rng: random.Random) -> tuple[Rule, ...]:
    return tuple(random_rule(space, rng) for _ in range(space.rules))


# -------------------------------------------------------------------------------------------- moves
def _tests(c: Cond) -> list[tuple[str, ...]]:
    """Paths to the tests of a condition ('l'/'r' steps)."""
    if isinstance(c, Test):
        return [()]
    if isinstance(c, (And, Or)):
        return [("l", *p) for p in _tests(c.left)] + [("r", *p) for p in _tests(c.right)]
    return []


def _get(c: Cond, path: tuple[str, ...]) -> Cond:
    for step in path:
        c = c.left if step == "l" else c.right  # type: ignore[union-attr]
    return c


def _set(c: Cond, path: tuple[str, ...], new: Cond) -> Cond:
    if not path:
        return new
    if path[0] == "l":
        return replace(c, left=_set(c.left, path[1:], new))  # type: ignore[union-attr, type-var]
    return replace(c, right=_set(c.right, path[1:], new))  # type: ignore[union-attr, type-var]


def _move_test(c: Cond, space: SearchSpace, rng: random.Random, how: str) -> Cond | None:
    paths = _tests(c)
    if not paths:
        return None
    path = rng.choice(paths)
    t: Test = _get(c, path)  # type: ignore[assignment]
    (name, w), = t.lhs.terms
    if how == "threshold":
        new = replace(t, threshold=_r2(t.threshold + rng.gauss(0.0, 0.1 * space.spread(name))))
    elif how == "feature":
        new = random_test(space, rng, rng.choice([f for f in space.features if f != name] or [name]))
    else:  # sign: f >= c  <->  -f >= -c  flips the side of the test
        new = Test(Linear(((name, -w),)), _r2(-t.threshold))
    return _set(c, path, new)


def _reshape(c: Cond, space: SearchSpace, rng: random.Random) -> Cond:
    if isinstance(c, TrueCond):
        return random_test(space, rng)
    if isinstance(c, Test):
        if space.max_depth >= 2 and rng.random() < 0.6:
            other = random_test(space, rng)
            op = rng.choice((And, Or))
            return op(c, other) if rng.random() < 0.5 else op(other, c)
        return TrueCond()
    assert isinstance(c, (And, Or))
    if rng.random() < 0.5:
        return (Or if isinstance(c, And) else And)(c.left, c.right)
    return c.left if rng.random() < 0.5 else c.right


def propose(rules: tuple[Rule, ...], space: SearchSpace, rng: random.Random) -> tuple[tuple[Rule, ...], str]:
    """A neighbour: one move applied to one rule. Returns (new rules, move name)."""
    for _ in range(20):  # some moves do not apply to some rules (no test to move, det mode): draw again
        k = rng.randrange(len(rules))
        r = rules[k]
        move = rng.choices(MOVES, _MOVE_WEIGHTS)[0]
        new: Rule | None = None
        if move in ("threshold", "feature", "sign"):
            if move != "threshold" and isinstance(r, ArgMaxRule) and rng.random() < 0.4:
                (name, w), = r.score.terms
                score = Linear(((name, -w),)) if move == "sign" else random_score(space, rng)
                new = replace(r, score=score)
            else:
                cond = _move_test(r.cond, space, rng, move)
                new = None if cond is None else replace(r, cond=cond)
        elif move == "shape":
            new = replace(r, cond=_reshape(r.cond, space, rng))
        elif move == "kind":
            if space.det:
                continue
            new = RandomRule(r.cond) if isinstance(r, ArgMaxRule) else ArgMaxRule(random_score(space, rng), r.cond)
        else:
            new = random_rule(space, rng)
        if new is not None and new != r:
            return rules[:k] + (new,) + rules[k + 1:], move
    return rules[:-1] + (random_rule(space, rng),), "rule"


# ------------------------------------------------------------------------------- the full neighbourhood
def grid(space: SearchSpace, name: str, sign: float) -> tuple[float, ...]:
    """The thresholds a test ``sign * name >= c`` can take on the quantile grid, ascending (world units)."""
    return _grid(tuple(space.quantiles[name]), sign)


@lru_cache(maxsize=4096)
def _grid(quantiles: tuple[float, ...], sign: float) -> tuple[float, ...]:
    # cached: every neighbourhood and fitting pass asks for the same few grids thousands of times
    return tuple(sorted({_r2(sign * q) for q in quantiles}))


def _rank(values: tuple[float, ...], c: float) -> int:
    """Index of the grid value nearest to c."""
    return min(range(len(values)), key=lambda i: abs(values[i] - c))


def _at_rank(space: SearchSpace, name: str, sign: float, frac: float) -> Test:
    """The test on ``name`` with sign ``sign`` at the grid value of relative rank ``frac`` (0 lowest, 1 highest)."""
    g = grid(space, name, sign)
    return Test(Linear(((name, sign),)), g[int(round(frac * (len(g) - 1)))])


def edits_of_test(t: Test, space: SearchSpace) -> list[tuple[Test, str]]:
    """Single edits of one test: its threshold to the next grid value below and above, an eighth of the grid below
    and above, and the grid's ends (MCMC's threshold moves jump as far); its feature swapped (same sign, same
    relative rank); its side flipped (f >= c to -f >= -c)."""
    (name, w), = t.lhs.terms
    g = grid(space, name, w)
    out: list[tuple[Test, str]] = []
    below = [c for c in g if c < t.threshold]
    above = [c for c in g if c > t.threshold]
    jump = max(2, len(g) // 8)
    moved = {below[-1] if below else None, above[0] if above else None, below[-jump] if len(below) >= jump else None,
             above[jump - 1] if len(above) >= jump else None, g[0], g[-1]} - {None, t.threshold}
    out += [(replace(t, threshold=c), "threshold") for c in sorted(moved)]  # type: ignore[type-var]
    frac = _rank(g, t.threshold) / max(len(g) - 1, 1)
    out += [(_at_rank(space, f, w, frac), "feature") for f in space.features if f != name]
    out.append((Test(Linear(((name, -w),)), _r2(-t.threshold)), "sign"))
    return out


def edits_of_cond(c: Cond, space: SearchSpace) -> list[tuple[Cond, str]]:
    """Single edits of a filter: each test edited (``edits_of_test``), each clause dropped, a clause added (a
    test on each feature and side at the median, alone or joined by and/or), and/or toggled."""
    out: list[tuple[Cond, str]] = []
    for path in _tests(c):
        out += [(_set(c, path, t), move) for t, move in edits_of_test(_get(c, path), space)]  # type: ignore[arg-type]
    fresh = [_at_rank(space, f, s, 0.5) for f in space.features for s in (1.0, -1.0)]
    if isinstance(c, TrueCond):
        out += [(t, "shape") for t in fresh]
    elif isinstance(c, Test):
        out.append((TrueCond(), "shape"))
        if space.max_depth >= 2:
            out += [(op(c, t), "shape") for op in (And, Or) for t in fresh if t.lhs != c.lhs]
    else:
        out += [(c.left, "shape"), (c.right, "shape"), ((Or if isinstance(c, And) else And)(c.left, c.right), "shape")]
    return out


def edits_of_rule(r: Rule, space: SearchSpace) -> list[tuple[Rule, str]]:
    """Single edits of one rule: its filter (``edits_of_cond``), its argmax score's feature or sign, its kind."""
    out: list[tuple[Rule, str]] = [(replace(r, cond=c), move) for c, move in edits_of_cond(r.cond, space)]
    scores = [Linear(((f, s),)) for f in space.score_features for s in (1.0, -1.0)]
    if isinstance(r, ArgMaxRule):
        out += [(replace(r, score=sc), "feature" if sc.terms[0][0] != r.score.terms[0][0] else "sign")
                for sc in scores if sc != r.score]
        if not space.det:
            out.append((RandomRule(r.cond), "kind"))
    else:
        out += [(ArgMaxRule(sc, r.cond), "kind") for sc in scores]
    return out


def neighbours(rules: tuple[Rule, ...], space: SearchSpace) -> list[tuple[tuple[Rule, ...], str]]:
    """Every single-edit neighbour of a round's rules (``edits_of_rule`` of each rule), with its move name:
    the hill-climbing neighbourhood of synth/local.py (``propose`` draws one such edit at random instead)."""
    return [(rules[:k] + (new,) + rules[k + 1:], move)
            for k, r in enumerate(rules) for new, move in edits_of_rule(r, space) if new != r]


def test_sites(rules: tuple[Rule, ...]) -> list[tuple[int, tuple[str, ...]]]:
    """(rule index, path) of every filter test of a round's rules: the coordinates of threshold fitting."""
    return [(k, path) for k, r in enumerate(rules) for path in _tests(r.cond)]


def test_at(rules: tuple[Rule, ...], site: tuple[int, tuple[str, ...]]) -> Test:
    k, path = site
    return _get(rules[k].cond, path)  # type: ignore[return-value]


def with_test(rules: tuple[Rule, ...], site: tuple[int, tuple[str, ...]], t: Test) -> tuple[Rule, ...]:
    """The rules with the test at ``site`` replaced by ``t``."""
    k, path = site
    return rules[:k] + (replace(rules[k], cond=_set(rules[k].cond, path, t)),) + rules[k + 1:]
