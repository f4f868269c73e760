"""Text form of programs: the paper's notation, one rule per line, exact (floats print as repr).

    argmax(map(-1.0*d, filter(theta >= -1.85, l)))
    random(filter(d >= 3.41 and gd >= 2.0, l))

A program with several rounds writes a ``round k:`` header before each round's rules. ``parser.parse`` is the
exact inverse: parse(to_text(p)) == p. ``describe`` gives a plain-language reading for people.
"""

from __future__ import annotations

import math

from .ast import And, ArgMaxRule, Cond, Linear, Or, Program, RandomRule, Rule, Test, TrueCond


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
_NAMES = {
    "d": "distance", "theta": "bearing (rad)", "dx": "x-offset", "dy": "y-offset",
    "gd": "own distance to goal", "gtheta": "bearing to own goal (rad)", "gx": "x-offset to own goal",
    "gy": "y-offset to own goal",
    "px": "own x-position", "py": "own y-position", "pd": "own distance from the origin",
}


def _lin_words(f: Linear) -> str:
    if len(f.terms) == 1:
        name, w = f.terms[0]
        word = _NAMES.get(name, name)
        return word if w == 1.0 else f"{fmt_float(w)} x {word}"
    return linear_text(f)


def _cond_words(c: Cond) -> str:
    if isinstance(c, TrueCond):
        return ""
    if isinstance(c, Test):
        if len(c.lhs.terms) == 1 and c.lhs.terms[0][1] == -1.0:
            return f"{_NAMES.get(c.lhs.terms[0][0], c.lhs.terms[0][0])} is at most {-c.threshold:.3g}"
        return f"{_lin_words(c.lhs)} is at least {c.threshold:.3g}"
    op = " and " if isinstance(c, And) else " or "
    parts = [w for w in (_cond_words(c.left), _cond_words(c.right)) if w]
    if len(parts) < 2:
        return parts[0] if parts else ""
    return "(" + op.join(parts) + ")"


def describe(r: Rule) -> str:
    """One plain-language line, e.g. 'ask the nearest agent whose bearing (rad) is at least -1.85'."""
    where = _cond_words(r.cond)
    whose = f" whose {where}" if where else ""
    if isinstance(r, RandomRule):
        return f"ask a random agent{whose}"
    if len(r.score.terms) == 1:
        name, w = r.score.terms[0]
        if name == "d":
            return f"ask the {'nearest' if w < 0 else 'farthest'} agent{whose}"
        word = _NAMES.get(name, name)
        return f"ask the agent with the {'smallest' if w < 0 else 'largest'} {word}{whose}"
    return f"ask the agent maximising {linear_text(r.score)}{whose}"
