"""Random programs and the MCMC neighbourhood over the grammar (paper section 3.4: 'standard neighbour programs').

Tests and scores use one feature with weight +-1, so programs read like the paper's
(``theta >= -1.85``, ``argmax(map(-1.0*d, ...))``); thresholds are drawn from the feature's empirical quantiles
and moved on a 0.01 grid, in world units. All randomness comes from a ``random.Random`` owned by the caller.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, replace

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
