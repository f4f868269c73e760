"""The program as data (program.json): the AST, the features it reads (meaning, unit, how each is computed from
an observation) and the rule semantics, so that any language can implement it. Stdlib only."""

from __future__ import annotations

import math

from ..dsl.ast import And, ArgMaxRule, Cond, Linear, Or, Program, RandomRule, Rule, Test, TrueCond
from ..dsl.printer import describe, rule_text, to_text
from ..dsl.vocabulary import Feature, FeatureSet
from ..errors import ConfigError
from . import SEMANTICS

FORMAT = "neurosym-program/1"

SEMANTICS_TEXT = (
    "For asking agent i among n agents (j = 0..n-1, i itself never a candidate), each rule of a round gives one "
    "agent index or -1. A filter passes j when its condition holds; a test 'sum_k w_k phi_k >= c' is evaluated "
    "with the terms summed in their written order. argmax(map(F, filter(B, l))): the passing j with the largest F, "
    "ties to the lowest index; -1 when no j passes. random(filter(B, l)): draws u_j from the uniform source for "
    "every j = 0..n-1 in index order (n draws, i and rejected agents included, also when nobody passes), then "
    "the passing j with the largest u_j, ties to the lowest index; -1 when no j passes. Random rules draw in rule "
    "order; argmax rules draw nothing. Agent i hears the union of its rules' picks: an agent picked by two rules "
    "is heard once, -1 means that rule adds nobody.")


def used_features(program: Program, vocab: FeatureSet, task: str) -> list[Feature]:
    """The features the program reads and those their products read, in the task's order; a feature without a
    source (only the task's own function knows it) cannot be exported: one line naming it."""
    need: set[str] = set()
    todo = list(program.features())
    while todo:
        name = todo.pop()
        if name in need:
            continue
        f = vocab.get(name)
        if f.source is None:
            raise ConfigError(f"feature {name!r} of task {task} has no source (Feature.source), so this program "
                              f"cannot be exported; declare it with Columns or column_feature (docs/extending.md)")
        need.add(name)
        todo += list(f.source.product)
    return [f for f in vocab.features if f.name in need]


def feature_json(f: Feature) -> dict:
    s = f.source
    assert s is not None
    src = ({"product": list(s.product)} if s.product else
           {"field": s.field, "start": s.start, "sign": s.sign, "part": s.part})
    return {"name": f.name, "of": f.of, "words": f.words, "unit": f.unit,
            "bounds": [_num(b) for b in f.bounds], "source": src}


def _num(x: float) -> float | str:
    """JSON has no infinity: 'inf' / '-inf' as strings."""
    return x if math.isfinite(x) else ("inf" if x > 0 else "-inf")


def linear_json(f: Linear) -> list:
    return [[name, w] for name, w in f.terms]


def cond_json(c: Cond) -> dict:
    if isinstance(c, TrueCond):
        return {"op": "true"}
    if isinstance(c, Test):
        return {"op": "test", "lhs": linear_json(c.lhs), "threshold": c.threshold}  # lhs >= threshold
    if isinstance(c, (And, Or)):
        return {"op": "and" if isinstance(c, And) else "or", "left": cond_json(c.left), "right": cond_json(c.right)}
    raise TypeError(f"not a condition: {c!r}")


def rule_json(r: Rule, vocab: FeatureSet) -> dict:
    out: dict = {"kind": "argmax" if isinstance(r, ArgMaxRule) else "random", "text": rule_text(r),
                 "reading": describe(r, vocab)}
    if isinstance(r, ArgMaxRule):
        out["score"] = linear_json(r.score)
    elif not isinstance(r, RandomRule):
        raise TypeError(f"not a rule: {r!r}")
    out["filter"] = cond_json(r.cond)
    return out


def check_finite(program: Program) -> None:
    """Every weight and threshold is a finite number (C and JSON have no literal for the others)."""
    def cond_ok(c: Cond) -> bool:
        if isinstance(c, Test):
            return math.isfinite(c.threshold) and all(math.isfinite(w) for _, w in c.lhs.terms)
        if isinstance(c, (And, Or)):
            return cond_ok(c.left) and cond_ok(c.right)
        return True
    for rules in program.rounds:
        for r in rules:
            ok = cond_ok(r.cond) and (not isinstance(r, ArgMaxRule) or all(math.isfinite(w) for _, w in r.score.terms))
            if not ok:
                raise ConfigError(f"rule {rule_text(r)!r} has a weight or threshold that is not a finite number")


def program_json(program: Program, vocab: FeatureSet, task: str, version: str, agent_dim: int,
                 pair_dim: int) -> dict:
    """program.json: everything an implementation in another language needs, and nothing of neurosym."""
    check_finite(program)
    feats = used_features(program, vocab, task)
    return {
        "format": FORMAT,
        "semantics": SEMANTICS,
        "semantics_text": SEMANTICS_TEXT,
        "task": task,
        "features_version": version,
        "inputs": {
            "me": f"s_i, the asking agent's own input, {agent_dim} floats (the task's agent observation)",
            "others": f"o_ij for j = 0..n-1, {pair_dim} floats each: agent i's view of agent j (row i ignored)",
        },
        "source_meaning": "a feature is the part (x, y, d = hypot(x, y), theta = atan2(y, x)) of the 2-D vector "
                          "sign * <field>[start:start + 2], field 'agent' = me, 'rel' = others[j]; or the product "
                          "of two features",
        "features": [feature_json(f) for f in feats],
        "rounds": [[rule_json(r, vocab) for r in rules] for rules in program.rounds],
        "text": to_text(program),
    }
