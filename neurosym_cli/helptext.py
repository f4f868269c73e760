"""`neurosym <command> --help`: what one command reads, each key with its value for this command line and the
first sentence of its schema's docstring (the typed schemas are the only description of a key), instead of Hydra's
dump of the whole composed config. ``commands.USES`` says which groups, keys and sections a command reads."""

from __future__ import annotations

import ast
import dataclasses
import inspect
import textwrap
from functools import lru_cache
from typing import Any, Callable

from .commands import COMMANDS, USES

GROUPS = ("task", "budget", "baseline")
WIDTH = 118


@lru_cache(maxsize=None)
def _own_docs(cls: type) -> dict[str, str]:
    """Field name -> the string literal written under it in ``cls``'s own body (attribute docstrings)."""
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    except (OSError, TypeError, SyntaxError):
        return {}
    body = tree.body[0].body if tree.body and isinstance(tree.body[0], ast.ClassDef) else []
    out = {}
    for a, b in zip(body, body[1:]):
        if (isinstance(a, ast.AnnAssign) and isinstance(a.target, ast.Name) and isinstance(b, ast.Expr)
                and isinstance(b.value, ast.Constant) and isinstance(b.value.value, str)):
            out[a.target.id] = b.value.value
    return out


def field_docs(cls: type) -> dict[str, str]:
    """Every field's docstring of a schema, its bases' included (a subclass's own wins)."""
    out: dict[str, str] = {}
    for c in reversed(cls.__mro__):
        out.update(_own_docs(c))
    return out


def first_sentence(doc: str) -> str:
    """The first sentence of a docstring (up to a '.' or ';' outside parentheses), on one line."""
    text, depth = " ".join(doc.split()), 0
    for i, ch in enumerate(text):
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if ch in ".;" and depth == 0 and (i + 1 == len(text) or text[i + 1] == " "):
            return text[:i]
    return text


def _value(v: Any) -> str:
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, list):
        return "[" + ",".join(_value(x) for x in v) + "]"
    if v is None:
        return "null"
    return "''" if v == "" else str(v)


def _rows(prefix: str, obj: Any, skip: tuple[str, ...] = ()) -> list[tuple[str, str]]:
    docs = field_docs(type(obj))
    return [(f"{prefix}{f.name}={_value(getattr(obj, f.name))}", first_sentence(docs.get(f.name, "")))
            for f in dataclasses.fields(obj) if f.name not in skip and not f.name.startswith("_")]


def _table(rows: list[tuple[str, str]]) -> list[str]:
    """``key=value`` left, its description wrapped in the right column (a long key gets a line of its own)."""
    left = min(max((len(k) for k, _ in rows), default=0), 34)
    out = []
    for k, doc in rows:
        if len(k) > left:
            out.append(f"  {k}")
            k = ""
        wrapped = textwrap.wrap(doc, WIDTH - left - 4) or [""]
        out.append(f"  {k:<{left}}  {wrapped[0]}".rstrip())
        out += [" " * (left + 4) + w for w in wrapped[1:]]
    return out


def _wrap(text: str, indent: int) -> list[str]:
    return textwrap.wrap(text, WIDTH, subsequent_indent=" " * indent) or [""]


def command_help(cmd: str, cfg: Any, choices: Callable[[str], list[str]]) -> str:
    """The help of ``neurosym <cmd>`` for the typed config ``cfg`` its command line composes."""
    uses = USES[cmd]
    lines = [f"usage: neurosym {cmd} [key=value ...] [-m] [--cfg job] [--help]", COMMANDS[cmd][1], ""]
    groups = [g for g in GROUPS if g in uses or f"{g}=" in uses]
    if groups:
        lines.append("config groups (key=option; * = this command line's):")
        for g in groups:
            now = getattr(cfg, g).name
            lines += _wrap(f"  {g:<9} " + ", ".join(f"{o}*" if o == now else o for o in choices(g)), 12)
        lines.append("")
    top = {f.name for f in dataclasses.fields(cfg)}
    keys = [k for k in uses if k in top and not dataclasses.is_dataclass(getattr(cfg, k)) and k not in GROUPS]
    rows = [r for r in _rows("", cfg) if r[0].split("=", 1)[0] in keys]
    lines += ["settings (as this command line has them):", *_table(rows), ""]
    sections = [k for k in uses if k in top and dataclasses.is_dataclass(getattr(cfg, k))]
    for name in sections:
        section = getattr(cfg, name)
        doc = first_sentence(inspect.getdoc(type(section)) or "")
        what = {"task": f"{cfg.task.name}, {type(section).__name__}", "budget": cfg.budget.name,
                "baseline": cfg.baseline.name}.get(name)
        lines += _wrap(f"{name}" + (f" ({what})" if what else "") + (f": {doc}" if doc else ""), 2)
        lines += [*_table(_rows(f"{name}.", section, skip=("name", "description"))), ""]
    lines.append(f"`neurosym {cmd} --cfg job` prints every value of the composed config; `neurosym --help` lists "
                 "the commands.")
    return "\n".join(lines) + "\n"
