"""Text form of programs: the paper's notation, one rule per line, exact (floats print as repr).

    argmax(map(-1.0*d, filter(theta >= -1.85, l)))
    random(filter(d >= 3.41 and gd >= 2.0, l))

A program with several rounds writes a ``round k:`` header before each round's rules. ``parser.parse`` is the
exact inverse: parse(to_text(p)) == p. ``describe`` gives a plain-language reading for people, in the words of the task's features (vocabulary.py).
"""

from __future__ import annotations

import math

from .ast import And, ArgMaxRule, Cond, Linear, Or, Program, RandomRule, Rule, Test, TrueCond, cond_features
from .vocabulary import FeatureSet


def fmt_float(x: float) -> str:
    """Shortest text that reads back as the same float."""
    return repr(float(x))


def linear_text(f: Linear) -> str:
    if not f.terms:
        return "0.0"
    parts = []
    for k, (name, w) in enumerate(f.terms):
        if k == 0:
            parts.append(name if w == 1.0 else f"{fmt_float(w)}*{name}")
        else:
            sign, mag = ("-", -w) if math.copysign(1.0, w) < 0 else ("+", w)  # -0.0 prints as "- 0.0"
            parts.append(f"{sign} {name}" if mag == 1.0 else f"{sign} {fmt_float(mag)}*{name}")
    return " ".join(parts)


def cond_text(c: Cond) -> str:
    if isinstance(c, TrueCond):
        return "true"
    if isinstance(c, Test):
        if len(c.lhs.terms) == 1 and c.lhs.terms[0][1] == -1.0:  # -f >= c reads better as f <= -c
            return f"{c.lhs.terms[0][0]} <= {fmt_float(-c.threshold)}"
        return f"{linear_text(c.lhs)} >= {fmt_float(c.threshold)}"
    op = "and" if isinstance(c, And) else "or"
    left = _wrapped(c.left, c, right=False)
    right = _wrapped(c.right, c, right=True)
    return f"{left} {op} {right}"


def _wrapped(child: Cond, parent: Cond, right: bool) -> str:
    """Parenthesise so that the text parses back to the same tree ('and' binds tighter, left-associative)."""
    text = cond_text(child)
    if isinstance(child, (And, Or)):
        needs = (isinstance(parent, And) and isinstance(child, Or)) or (right and type(child) is type(parent))
        if needs:
            return f"({text})"
    return text


def rule_text(r: Rule) -> str:
    if isinstance(r, ArgMaxRule):
        return f"argmax(map({linear_text(r.score)}, filter({cond_text(r.cond)}, l)))"
    return f"random(filter({cond_text(r.cond)}, l))"


def to_text(p: Program) -> str:
    """The canonical text of a program (ends with a newline)."""
    if p.n_rounds == 1:
        return "".join(rule_text(r) + "\n" for r in p.rounds[0])
    lines = []
    for k, rules in enumerate(p.rounds, start=1):
        lines.append(f"round {k}:")
        lines += [f"  {rule_text(r)}" for r in rules]
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------------- plain language
# A filter's clauses are of two kinds (FeatureSet.agent_level): those on the asking agent's own state are the
# same for every candidate, so they decide whether the agent asks anybody at all (a guard: "while my distance to
# my goal is at least 7.46, ..."); those on the other agent select among the candidates ("... within 2.06").
# A score that reads only the agent's own state ties every candidate, and argmax then takes the lowest index.


def _own(c: Cond, v: FeatureSet) -> bool | None:
    """True if every feature of c describes the asking agent, False if every one the other agent, None if mixed
    (TrueCond counts as the asking agent's)."""
    names = cond_features(c)
    if all(v.agent_level(n) for n in names):
        return True
    if not any(v.agent_level(n) for n in names):
        return False
    return None


def _num(x: float) -> str:
    """A threshold as the rule prints it (the same digits in the rule and in its reading)."""
    return fmt_float(x)


def _test_words(t: Test, v: FeatureSet) -> str:
    """'my distance to my goal is at least 7.46', 'its distance is at most 2.06' (a test alone)."""
    if len(t.lhs.terms) == 1:
        name, w = t.lhs.terms[0]
        subject = v.words(name)
        if w == 1.0:
            return f"{subject} is at least {_num(t.threshold)}"
        if w == -1.0:
            return f"{subject} is at most {_num(-t.threshold)}"
        return f"{fmt_float(w)} x {subject} is at least {_num(t.threshold)}"
    return f"{linear_text(t.lhs)} is at least {_num(t.threshold)}"


def _cond_words(c: Cond, v: FeatureSet) -> str:
    """Any condition, each clause with its subject ('my ...', 'its ...'); and binds tighter than or."""
    if isinstance(c, TrueCond):
        return "always"
    if isinstance(c, Test):
        return _test_words(c, v)
    op = " and " if isinstance(c, And) else " or "
    return "(" + _cond_words(c.left, v) + op + _cond_words(c.right, v) + ")"


def _bare(c: Cond, v: FeatureSet) -> str:
    """_cond_words without the outer parentheses."""
    text = _cond_words(c, v)
    return text[1:-1] if isinstance(c, (And, Or)) else text


def _selection(c: Cond, v: FeatureSet) -> str:
    """A clause on the other agent, as a phrase after 'agent': 'within 2.06', 'whose bearing (rad) is ...'."""
    if isinstance(c, Test) and len(c.lhs.terms) == 1:
        name, w = c.lhs.terms[0]
        if v.get(name).distance and w == -1.0:
            return f"within {_num(-c.threshold)}"
        if v.get(name).distance and w == 1.0:
            return f"at least {_num(c.threshold)} away"
        text = _test_words(c, v)
        return "whose " + text[len("its "):] if text.startswith("its ") else f"for which {text}"
    return f"for which {_bare(c, v)}"


def _conjuncts(c: Cond) -> list[Cond]:
    if isinstance(c, And):
        return _conjuncts(c.left) + _conjuncts(c.right)
    return [] if isinstance(c, TrueCond) else [c]


def _pick(r: Rule, v: FeatureSet) -> tuple[str, str]:
    """(who is asked, a note on a score that ties every candidate)."""
    if isinstance(r, RandomRule):
        return "a random agent", ""
    terms = r.score.terms
    if all(v.agent_level(n) for n, _ in terms):
        what = v.words(terms[0][0]) if len(terms) == 1 else linear_text(r.score)
        return "the lowest-index agent", (f" (the score, {what}, is the same for every candidate, so argmax falls to "
                                          f"agent order)")
    if len(terms) == 1:
        name, w = terms[0]
        if v.get(name).distance:
            return f"the {'nearest' if w < 0 else 'farthest'} agent", ""
        subject = v.words(name).removeprefix("its ")
        return f"the agent with the {'smallest' if w < 0 else 'largest'} {subject}", ""
    return f"the agent maximising {linear_text(r.score)}", ""


def describe(r: Rule, vocab: FeatureSet) -> str:
    """One plain-language line that separates the rule's guard (clauses on the asking agent's own state) from its
    selection (clauses and score on the other agent), e.g. 'while my distance to my goal is at least 7.46, ask a
    random agent within 2.06; otherwise ask nobody'."""
    v = vocab
    pick, note = _pick(r, v)
    guards, selections, options = [], [], []
    for c in _conjuncts(r.cond):
        own = _own(c, v)
        if own:
            guards.append(_bare(c, v))
        elif own is False:
            selections.append(_selection(c, v))
        elif isinstance(c, Or) and _own(c.left, v) is not None and _own(c.right, v) is not None:
            mine, other = (c.left, c.right) if _own(c.left, v) else (c.right, c.left)
            if _own(mine, v) and _own(other, v) is False:
                options.append(f"any agent if {_bare(mine, v)}, otherwise only those "
                               f"{_selection(other, v)}")
            else:
                selections.append(_selection(c, v))
        else:
            selections.append(_selection(c, v))
    body = f"ask {pick}" + (" " + " and ".join(selections) if selections else "")
    body += "".join(f" ({o})" for o in options) + note
    if guards:
        return f"while {' and '.join(guards)}, {body}; otherwise ask nobody"
    return body
