"""The communication-program language of paper section 3.2, as plain immutable data.

    Program  ::= one tuple of rules per communication round
    Rule     ::= argmax(map(F, filter(B, l)))  |  random(filter(B, l))
    B        ::= true | F >= c | B and B | B or B
    F        ::= sum_k w_k * phi_k            (a sparse linear form over named features)

Nodes hold only floats, strings and tuples, so they are hashable, comparable and free of tensors and
devices; ``interpret.py`` gives them meaning on a feature tensor, ``printer.py`` and ``parser.py`` are the
exact text form.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Union


@dataclass(frozen=True)
class Linear:
    """sum_k w_k * phi_k over named features (a map score F, or the left side of a test)."""

    terms: tuple[tuple[str, float], ...]  # ((feature name, weight), ...), each name at most once

    def features(self) -> tuple[str, ...]:
        return tuple(n for n, _ in self.terms)


@dataclass(frozen=True)
class TrueCond:
    """Passes every other agent."""


@dataclass(frozen=True)
class Test:
    """<beta, phi(s_i, o_ij)> >= 0, written as ``lhs >= threshold`` (the threshold is minus beta's bias)."""

    lhs: Linear
    threshold: float


@dataclass(frozen=True)
class And:
    left: "Cond"
    right: "Cond"


@dataclass(frozen=True)
class Or:
    left: "Cond"
    right: "Cond"


Cond = Union[TrueCond, Test, And, Or]


@dataclass(frozen=True)
class ArgMaxRule:
    """argmax(map(score, filter(cond, l))): the filtered agent with the best score; nobody if none passes."""

    score: Linear
    cond: Cond


@dataclass(frozen=True)
class RandomRule:
    """random(filter(cond, l)): a uniformly random filtered agent; nobody if none passes."""

    cond: Cond


Rule = Union[ArgMaxRule, RandomRule]


@dataclass(frozen=True)
class Program:
    """One tuple of rules per communication round (paper appendix A: one program per round)."""

    rounds: tuple[tuple[Rule, ...], ...]

    @property
    def n_rounds(self) -> int:
        return len(self.rounds)

    @property
    def max_rules(self) -> int:
        """K: the most rules of any round (a bound on every agent's in-degree)."""
        return max((len(r) for r in self.rounds), default=0)

    def features(self) -> set[str]:
        """Every feature name the program reads."""
        out: set[str] = set()
        for rules in self.rounds:
            for r in rules:
                out |= rule_features(r)
        return out

    @property
    def deterministic(self) -> bool:
        return all(isinstance(r, ArgMaxRule) for rules in self.rounds for r in rules)


def cond_features(c: Cond) -> set[str]:
    if isinstance(c, Test):
        return set(c.lhs.features())
    if isinstance(c, (And, Or)):
        return cond_features(c.left) | cond_features(c.right)
    return set()


def rule_features(r: Rule) -> set[str]:
    out = cond_features(r.cond)
    if isinstance(r, ArgMaxRule):
        out |= set(r.score.features())
    return out
