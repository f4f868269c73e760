"""What each rule of a synthesized program does on the synthesis dataset D, and a simplification step.

Statistics per rule (one communication round): how often it fires (picks somebody), its share of the program's
edges (an edge two rules pick counts for the first), and the objective change when it is removed. Flags: a rule
that never or always fires, a filter clause that can never hold (``d >= 3 and d <= 2``; a distance below zero;
an angle beyond pi), a clause that holds for every pair of D or for none.

Simplification keeps the objective: it drops filter clauses that change no pick on D (a clause that always holds
inside an ``and``, never holds inside an ``or``, or can never hold; an ``or`` whose one-feature branches cover the
feature's range always holds) and rules that never fire, and keeps a change only when the objective the search
minimised is not worse (dropping a rule renumbers the random rules after it, which then draw other random numbers,
so that is checked, never assumed). ``simplify_static`` makes the data-free part of it for a program alone.
"""

from __future__ import annotations

import math
from dataclasses import replace

import torch

from ..dsl.ast import And, Cond, Or, Rule, Test, TrueCond
from ..dsl.vocabulary import FeatureSet
from ..dsl.interpret import cond, dedup_valid
from ..dsl.printer import cond_text, rule_text
from .objective import CachedScorer

def _range(name: str, vocab: FeatureSet) -> tuple[float, float]:
    """The values a feature can take at all, as the task declares them (norms are >= 0, angles lie in (-pi, pi])."""
    return vocab.bounds(name) if name in vocab else (-math.inf, math.inf)


def _bounds(t: Test) -> tuple[str, float, float] | None:
    """A one-feature test as (feature, lower, upper): w f >= c is f >= c / w (w > 0) or f <= c / w (w < 0)."""
    if len(t.lhs.terms) != 1:
        return None
    name, w = t.lhs.terms[0]
    if w == 0:
        return None
    return (name, t.threshold / w, math.inf) if w > 0 else (name, -math.inf, t.threshold / w)


def _disjuncts(c: Cond) -> list[Cond]:
    return _disjuncts(c.left) + _disjuncts(c.right) if isinstance(c, Or) else [c]


def _covered(c: Or, vocab: FeatureSet) -> bool:
    """Whether the one-feature branches of an ``or`` chain cover a feature's whole range between them
    (``d <= 2.85 or d >= 2.56``: every distance is below 2.85 or above 2.56)."""
    spans: dict[str, list[tuple[float, float]]] = {}
    for p in _disjuncts(c):
        b = _bounds(p) if isinstance(p, Test) else None
        if b is not None:
            spans.setdefault(b[0], []).append((b[1], b[2]))
    for name, parts in spans.items():
        reach, top = _range(name, vocab)  # covered from the bottom of the range up to `reach`
        for lo, hi in sorted(parts):
            if lo > reach:
                break  # a gap: values in (reach, lo) pass no branch
            reach = max(reach, hi)
        if reach >= top:
            return True
    return False


def always_holds(c: Cond, vocab: FeatureSet) -> bool:
    """True when every pair passes ``c``, whatever the data: ``true``, a bound every value of the feature meets
    (``d >= -0.6``: a distance is never negative), an ``or`` with such a branch, or an ``or`` whose one-feature
    branches cover the feature's range (``d <= 2.85 or d >= 2.56``)."""
    if isinstance(c, TrueCond):
        return True
    if isinstance(c, Or):
        return any(always_holds(p, vocab) for p in _disjuncts(c)) or _covered(c, vocab)
    if isinstance(c, And):
        return always_holds(c.left, vocab) and always_holds(c.right, vocab)
    b = _bounds(c) if isinstance(c, Test) else None
    if b is None:
        return False
    lo0, hi0 = _range(b[0], vocab)
    return b[1] <= lo0 and b[2] >= hi0


def _conjuncts(c: Cond) -> list[Cond]:
    return _conjuncts(c.left) + _conjuncts(c.right) if isinstance(c, And) else [c]


def never_holds(c: Cond, vocab: FeatureSet) -> bool:
    """True when no pair of agents can pass ``c``, whatever the data: contradictory bounds on one feature inside
    an ``and`` chain, or a bound outside the feature's range."""
    if isinstance(c, Or):
        return never_holds(c.left, vocab) and never_holds(c.right, vocab)
    parts = _conjuncts(c)
    if any(isinstance(p, Or) and never_holds(p, vocab) for p in parts):
        return True
    box: dict[str, tuple[float, float]] = {}
    for p in parts:
        b = _bounds(p) if isinstance(p, Test) else None
        if b is None:
            continue
        name, lo, hi = b
        lo0, hi0 = box.get(name, _range(name, vocab))
        box[name] = (max(lo0, lo), min(hi0, hi))
    return any(lo > hi for lo, hi in box.values())


def _pass_rate(scorer: CachedScorer, c: Cond) -> float:
    """Fraction of the (state, agent i, other agent j) triples of D for which ``c`` holds."""
    hit, total = 0.0, 0
    for d in scorer.data:
        m = cond(c, d.feats).expand(d.s, d.n, d.n)
        off = ~torch.eye(d.n, dtype=torch.bool, device=m.device)
        hit += float(m[:, off].float().sum())
        total += d.s * d.n * (d.n - 1)
    return hit / max(total, 1)


def _clauses(c: Cond, path: tuple = ()) -> list[tuple[tuple, Cond, str]]:
    """Every clause under an and/or, with its path and the operator it sits under ('and', 'or')."""
    out = []
    if isinstance(c, (And, Or)):
        op = "and" if isinstance(c, And) else "or"
        for side in ("left", "right"):
            child = getattr(c, side)
            out.append((path + (side,), child, op))
            out += _clauses(child, path + (side,))
    return out


def _drop(c: Cond, path: tuple) -> Cond:
    """``c`` with the clause at ``path`` removed (its and/or replaced by the other side)."""
    side, rest = path[0], path[1:]
    if not rest:
        return c.right if side == "left" else c.left  # type: ignore[union-attr]
    return replace(c, **{side: _drop(getattr(c, side), rest)})


def rule_stats(scorer: CachedScorer, rules: tuple[Rule, ...]) -> list[dict]:
    """Per rule: fires (fraction of (state, agent) where it picks somebody), edge_share (of the program's edges),
    removal_delta (objective without it minus with it: positive means the rule helps), flags."""
    per_rule = [scorer.picks_of(r, k) for k, r in enumerate(rules)]
    fires = [0.0] * len(rules)
    edges = [0.0] * len(rules)
    rows = 0
    for bi in range(len(scorer.data)):
        for s in range(scorer.samples):
            picks = torch.stack([p[bi][min(s, p[bi].shape[0] - 1)] for p in per_rule], -1).long()  # (S N, K)
            valid = dedup_valid(picks)
            for k in range(len(rules)):
                fires[k] += float((picks[:, k] >= 0).sum())
                edges[k] += float(valid[:, k].sum())
            rows += picks.shape[0]
    base = scorer.score(rules).total
    total_edges = sum(edges)
    out = []
    for k, r in enumerate(rules):
        without = rules[:k] + rules[k + 1:]
        delta = (scorer.score(without).total - base) if without else math.nan
        rate = fires[k] / max(rows, 1)
        flags = []
        if rate == 0.0:
            flags.append("never fires")
        elif rate == 1.0:
            flags.append("always fires")
        for _, clause, _ in _clauses(r.cond) or [((), r.cond, "")]:
            if isinstance(clause, TrueCond):
                continue
            if never_holds(clause, scorer.fmap.vocab):
                flags.append(f"`{cond_text(clause)}` can never hold")
        out.append({"rule": k + 1, "text": rule_text(r), "fires": rate,
                    "edge_share": edges[k] / total_edges if total_edges else 0.0,
                    "removal_delta": delta, "flags": flags})
    return out


def simplify(scorer: CachedScorer, rules: tuple[Rule, ...], tol: float = 1e-9) -> tuple[tuple[Rule, ...], list[str]]:
    """Drop clauses and rules that do nothing on D while the objective stays the same (or improves); returns
    the simplified rules and one line per change made (and per never-firing rule kept, with the reason)."""
    best = scorer.score(rules).total
    done: list[str] = []
    changed = True
    while changed:
        changed = False
        for k, r in enumerate(rules):
            if isinstance(r.cond, Or) and (always_holds(r.cond, scorer.fmap.vocab) or _pass_rate(scorer, r.cond) == 1.0):
                cand = rules[:k] + (replace(r, cond=TrueCond()),) + rules[k + 1:]
                new = scorer.score(cand).total
                if new <= best + tol * max(1.0, abs(best)):
                    why = "always holds" if always_holds(r.cond, scorer.fmap.vocab) else "holds for every pair of D"
                    done.append(f"rule {k + 1}: filter `{cond_text(r.cond)}` became `true` ({why}); "
                                f"objective {best:.4f} -> {new:.4f}")
                    rules, best, changed = cand, new, True
                    break
            for path, clause, op in _clauses(r.cond):
                rate = 0.0 if never_holds(clause, scorer.fmap.vocab) else _pass_rate(scorer, clause)
                idle = (op == "and" and (rate == 1.0 or always_holds(clause, scorer.fmap.vocab))) or (op == "or" and rate == 0.0) \
                    or never_holds(clause, scorer.fmap.vocab)
                if not idle:
                    continue
                if op == "and" and never_holds(clause, scorer.fmap.vocab):
                    continue  # an impossible conjunct makes the whole and impossible: not a no-op to drop
                cand = rules[:k] + (replace(r, cond=_drop(r.cond, path)),) + rules[k + 1:]
                new = scorer.score(cand).total
                if new <= best + tol * max(1.0, abs(best)):
                    why = ("can never hold" if never_holds(clause, scorer.fmap.vocab) else "always holds" if always_holds(clause, scorer.fmap.vocab) else
                           "holds for every pair of D" if rate == 1.0 else "holds for no pair of D")
                    done.append(f"rule {k + 1}: dropped `{cond_text(clause)}` from its filter ({why}); "
                                f"objective {best:.4f} -> {new:.4f}")
                    rules, best, changed = cand, new, True
                    break
            if changed:
                break
    # rules that add no edge on D (never fire, or only repeat an earlier rule's pick), from the last one:
    # dropping a rule renumbers only the rules after it
    for k in range(len(rules) - 1, -1, -1):
        if len(rules) == 1:
            break
        r = rules[k]
        if _edges_added(scorer, rules, k) > 0:
            continue
        why = "never fires on D" if all(bool((p < 0).all()) for p in scorer.picks_of(r, k)) else \
            "only repeats earlier rules' picks on D"
        cand = rules[:k] + rules[k + 1:]
        new = scorer.score(cand).total
        if new <= best + tol * max(1.0, abs(best)):
            done.append(f"rule {k + 1}: dropped `{rule_text(r)}` ({why}); objective {best:.4f} -> {new:.4f}")
            rules, best = cand, new
        else:
            done.append(f"rule {k + 1}: kept `{rule_text(r)}` although it {why}: "
                        f"without it the random rules after it draw other random numbers and the objective goes "
                        f"from {best:.4f} to {new:.4f}")
    return rules, done


def simplify_static(rules: tuple[Rule, ...], vocab: FeatureSet) -> tuple[tuple[Rule, ...], list[str]]:
    """The rewrites that hold whatever the data, for a program without its dataset D (a committed result, a
    hand-written file): a filter that always holds becomes ``true``, a clause that always holds leaves its ``and``,
    one that never holds leaves its ``or``, and a rule whose filter never holds (it never fires) is dropped.
    Returns the rules and one line per change. A dropped rule renumbers the random rules after it (their random
    numbers differ, their distribution does not); ``simplify`` checks such a change on D, this one only reads."""
    notes: list[str] = []
    out = []
    for k, r in enumerate(rules, start=1):
        c = r.cond
        if not isinstance(c, TrueCond) and always_holds(c, vocab):
            notes.append(f"rule {k}: filter `{cond_text(c)}` is `true` (it always holds)")
            c = TrueCond()
        changed = True
        while changed:
            changed = False
            for path, clause, op in _clauses(c):
                if (op == "and" and always_holds(clause, vocab)) or (op == "or" and never_holds(clause, vocab)):
                    why = "always holds" if op == "and" else "can never hold"
                    notes.append(f"rule {k}: dropped `{cond_text(clause)}` from its filter ({why})")
                    c, changed = _drop(c, path), True
                    break
        if never_holds(c, vocab):
            notes.append(f"rule {k}: dropped `{rule_text(r)}`: it never fires (`{cond_text(c)}` can never hold)")
            continue
        out.append(replace(r, cond=c))
    if not out:  # nothing ever fires: the program says so as it is
        return rules, notes
    return tuple(out), notes


def _edges_added(scorer: CachedScorer, rules: tuple[Rule, ...], k: int) -> int:
    """How many edges of D rule k adds that no earlier rule picked (over every bucket and random sample)."""
    per_rule = [scorer.picks_of(r, j) for j, r in enumerate(rules[:k + 1])]
    added = 0
    for bi in range(len(scorer.data)):
        for s in range(scorer.samples):
            picks = torch.stack([p[bi][min(s, p[bi].shape[0] - 1)] for p in per_rule], -1).long()
            added += int(dedup_valid(picks)[:, k].sum())
    return added

