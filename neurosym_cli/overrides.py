"""Command-line overrides checked before Hydra sees them (stdlib only): a typo in a key or a value of the wrong
type is one line naming the closest key or the expected type, instead of Hydra's multi-line message that suggests
``+key=value`` (which would then be accepted and ignored)."""

from __future__ import annotations

import dataclasses
import difflib
import os
import re
import unicodedata

from .config import RunConfig, TaskConfig
from .errors import cut
from .schemes import SCHEMES

_SCHEMAS = {f.name: type(f.default_factory()) for f in dataclasses.fields(RunConfig)  # type: ignore[misc]
            if f.name != "task" and f.default_factory is not dataclasses.MISSING
            and dataclasses.is_dataclass(f.default_factory())}
"""the config sections (model, optim, budget, baseline, synth, render, ...): every dataclass field of RunConfig"""
_SECTIONS = tuple(_SCHEMAS)
_GROUPS = ("task", "baseline", "budget")  # config groups: key=<option name>
_FUNCS = ("range(", "choice(", "glob(", "interval(", "shuffle(", "sort(", "tag(", "str(", "int(", "float(", "bool(")
_INT = re.compile(r"[+-]?[0-9][0-9_]*")
_BOOL = {"true", "false"}  # only these: yes, on and 1 would pass for true here and nowhere else (issue 38)


def _fields(cls) -> dict[str, str]:
    return {f.name: str(f.type) for f in dataclasses.fields(cls)}


def known_keys(task_schemas: list[type] | None = None) -> dict[str, str]:
    """Every key an override may set, dotted, with its declared type (as written in the schemas); ``task.*`` keys
    are those of the schemas of the tasks the command line runs (the base TaskConfig when none is known)."""
    top = _fields(RunConfig)
    keys = {k: t for k, t in top.items() if k not in _SECTIONS + ("task",)}
    keys.update({g: "group" for g in _GROUPS})
    for section in _SECTIONS:
        keys.update({f"{section}.{k}": t for k, t in _fields(_SCHEMAS[section]).items()})
    for schema in task_schemas or [TaskConfig]:
        keys.update({f"task.{k}": t for k, t in _fields(schema).items()})
    for scheme in SCHEMES.values():  # a scheme's own fields (baseline.det, baseline.radius)
        keys.update({f"baseline.{k}": t for k, t in _fields(type(scheme)).items()})
    return keys


_KINDS = {"int": "an integer", "float": "a number", "bool": "true or false", "str": "a text"}


@dataclasses.dataclass(frozen=True)
class NumberKind:
    """A numeric type of the schemas (int, float): which ASCII words it reads, and how its hints name it."""

    name: str
    many: str
    """the plural in a hint: integers, numbers"""
    fractional: bool
    """a fraction part is allowed (½, 0,5, 0.5)"""
    example: str
    examples: str

    @property
    def one(self) -> str:
        return _KINDS[self.name]

    @property
    def how(self) -> str:
        return "ASCII digits" + (" and '.' for the decimal point" if self.fractional else "")

    def reads(self, word: str) -> bool:
        """Whether the ASCII ``word`` is a value of this kind as a config reads it."""
        if not self.fractional:
            return _INT.fullmatch(word) is not None
        try:
            float(word.replace("_", ""))
        except ValueError:
            return False
        return True


NUMBERS = {k.name: k for k in (NumberKind("int", "integers", False, "1", "[1,2]"),
                               NumberKind("float", "numbers", True, "0.5", "[0.3,0.5]"))}
"""the schemas' numeric type names -> their kinds"""


def _unquote(value: str) -> str:
    return value[1:-1] if len(value) > 1 and value[0] == value[-1] and value[0] in "'\"" else value


def _type_error(value: str, typ: str) -> str | None:
    """Why ``value`` cannot be a ``typ`` (int, float, bool; list[...] of them), or None when it can (or cannot be
    judged here: interpolations, sweep functions, dictionaries)."""
    if value.startswith(("${", "{")) or value.startswith(_FUNCS) or value == "null":  # null: check() judges it
        return None
    if typ.startswith("list["):
        inner = typ[5:-1]
        if not (value.startswith("[") and value.endswith("]")) or inner not in ("int", "float", "bool"):
            return None  # a sweep over lists, or a list of texts: Hydra's grammar check judges it
        bad = [_type_error(v.strip(), inner) for v in value[1:-1].split(",") if v.strip()]
        return next((f"a list of {w.removeprefix('an ').removeprefix('a ')}s" for w in bad if w), None)
    if value.startswith("["):
        return f"one value ({_KINDS[typ]}), not a list; -m key=a,b sweeps over values"
    for part in value.split(",") if value[:1] not in "'\"" else [value]:  # a sweep: seed=0,1,2
        part = _unquote(part.strip())
        if typ in NUMBERS and not NUMBERS[typ].reads(part):
            return _KINDS[typ]
        if typ == "bool" and part.lower() not in _BOOL:
            return _KINDS[typ]
    return None


_DECIMAL_COMMA = re.compile(r"[+-]?[0-9]+,[0-9]+")


def _ascii_number(text: str, kind: NumberKind) -> str | None:
    """``text``, a number of ``kind`` written with other scripts' digits, fullwidth forms (``０.５``), a vulgar
    fraction (``½``, ``1½``) or a decimal comma (``0,5``), in the ASCII a config reads; None when it is no such
    number."""
    text = text.strip()
    last = text[-1:]
    frac = unicodedata.numeric(last, None) if last and not last.isascii() else None
    if frac is not None and frac % 1:  # a vulgar fraction, after an optional whole part
        whole = _ascii_number(text[:-1], NUMBERS["int"]) if text[:-1] else "0"
        if whole is None or not kind.fractional:
            return None
        return f"{'-' if whole.startswith('-') else ''}{abs(int(whole)) + frac:g}"
    out = []
    for ch in unicodedata.normalize("NFKC", text):  # fullwidth and other compatibility forms
        digit = unicodedata.decimal(ch, None)
        out.append(ch if ch.isascii() else str(digit) if digit is not None else "-" if ch in "\u2212\u2013"
                   else "." if ch == "\u066b" else "?")  # the minus signs; the Arabic decimal separator
    word = "".join(out)
    if kind.fractional and _DECIMAL_COMMA.fullmatch(word):
        word = word.replace(",", ".")
    if not kind.reads(word):
        return None
    return word if word.isascii() and word.lower().lstrip("+-") not in ("inf", "nan", "infinity") else None


def number_hint(key: str, value: str, keys: dict[str, str]) -> str | None:
    """How to write a number the config reads, when ``value`` of the numeric key ``key`` (an int or float, or a
    list of them) is written with characters other than ASCII digits and a point (``lam=０.５``, ``lam=½``,
    ``lam=0,5``): one line naming the key and, where it can be read, the ASCII form; else None."""
    typ = keys.get(key, "")
    typ = typ.removeprefix("Optional[").removesuffix("]") if typ.startswith("Optional[") else typ
    listed = typ.startswith("list[") and value.startswith("[") and value.endswith("]")
    kind = NUMBERS.get(typ[5:-1] if listed else typ)
    if kind is None:
        return None
    value = _unquote(value)
    parts = [p.strip() for p in value[1:-1].split(",")] if listed else [value]
    decimal_comma = not listed and kind.fractional and _DECIMAL_COMMA.fullmatch(value) is not None
    if all(p.isascii() for p in parts) and not decimal_comma:
        return None
    fixed = [_ascii_number(p, kind) for p in parts]
    fix = None if None in fixed else f"[{','.join(fixed)}]" if listed else fixed[0]  # type: ignore[arg-type]
    what = kind.many if listed else kind.one
    return (f"{key} takes {'a list of ' if listed else ''}{what} written in {kind.how}, not {cut(repr(value))}"
            + (f"; write {key}={fix}" if fix else f"; e.g. {key}={kind.examples if listed else kind.example}"))


_INTERPOLATION = re.compile(r"\$\{([^${}]*)\}")  # the innermost ${...} of a value
_INT64 = 2**63


def _interpolation_problem(value: str, keys: dict[str, str]) -> str | None:
    """Why an interpolation in an override's value cannot resolve (a key no config has, an unset environment
    variable without a default), or None; resolvers other than oc.env are left to Hydra."""
    for m in _INTERPOLATION.finditer(value):
        body = m.group(1).strip()
        if body.startswith("oc.env:"):
            var, sep, _ = body[len("oc.env:"):].partition(",")
            if not sep and var.strip() not in os.environ:
                return (f"the environment variable {var.strip()} is not set; set it, or give a default: "
                        f"${{oc.env:{var.strip()},VALUE}}")
        elif ":" not in body and body not in keys and not body.startswith(("hydra", ".")):
            near = difflib.get_close_matches(body, list(keys), n=1, cutoff=0.6)
            return f"${{{body}}} names no key of the config" + (f"; did you mean ${{{near[0]}}}?" if near else "")
    return None


def _int_problem(value: str) -> str | None:
    """Why an integer override's value does not fit the 64 bits every consumer (torch, numpy, Hydra) takes."""
    for part in value.split(","):
        part = part.strip().replace("_", "")
        if _INT.fullmatch(part) and not -_INT64 <= int(part) < _INT64:
            return f"{cut(part, 40)} is beyond a 64-bit integer (-2^63 to 2^63 - 1)"
    return None


def check(args: list[str], task_schemas: list[type] | None = None) -> str | None:
    """A one-line error for the first bad override in ``args`` (flags and Hydra's own keys are skipped), else None.
    ``task_schemas``: the schemas of the tasks the command line runs (their own keys are known)."""
    keys = known_keys(task_schemas)
    for a in args:
        if a.startswith("-") or "=" not in a and not a.startswith("~"):
            continue
        key, _, value = a.partition("=")
        removed = key.startswith("~")
        key = key.lstrip("+~")
        if key.startswith("hydra") or "/" in key or "@" in key:
            continue
        if removed and key in keys:  # every key is part of the typed config: removing one leaves it missing
            what = f"choose another one ({key}=...)" if keys[key] == "group" else f"set it instead ({key}=...)"
            return f"{cut(a)}: {key} cannot be removed, every command reads it; {what}"
        why = _interpolation_problem(value, keys)
        if why:
            return f"{cut(a)}: {why}"
        hint = number_hint(key, value, keys)
        if hint:
            return f"{cut(a)}: {hint}"
        if not all(ch.isascii() for ch in value) and not value.startswith(("'", '"')):
            return (f"{cut(a)}: Hydra reads non-ASCII characters only in quotes; write it as \"{key}='{cut(value)}'\" "
                    f"(the double quotes are for the shell)")
        if key not in keys:
            near = difflib.get_close_matches(key, list(keys), n=1, cutoff=0.6)
            hint = f"; did you mean {near[0]!r}?" if near else "; `neurosym <command> --cfg job` lists the keys"
            return f"unknown key {cut(repr(key))}{hint}"
        optional = keys[key].startswith("Optional[")
        typ = keys[key].removeprefix("Optional[").removesuffix("]") if optional else keys[key]
        if value == "null" and not optional and typ != "group" and not a.startswith("~"):
            kind = _KINDS.get(typ, "a list [a,b]" if typ.startswith("list[") else "a value")
            return f"{a}: {key} cannot be null; it takes {kind}" + (f" (an empty one: {key}='')" if typ == "str" else "")
        if typ == "str" and value.startswith("[") and value.endswith("]"):  # Hydra's "Error merging override"
            return (f"{cut(a)}: {key} takes one value, not a list"
                    + ("; join trackers by + (logger=tensorboard+mlflow)" if key == "logger" else ""))
        if typ in ("int", "float", "bool") or typ.startswith("list["):
            why = _type_error(value, typ)
            if why:
                return f"{cut(a)}: {key} takes {why}, not {cut(repr(value))}"
            why = _int_problem(value) if typ == "int" else None
            if why:
                return f"{cut(a)}: {key} takes a 64-bit integer; {why}"
    return None
