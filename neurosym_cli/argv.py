"""The command line read before Hydra sees it: a word that is not an override (``random-grid``, ``tiny``), a flag
in another tool's style (``--task random-grid``), and what Hydra's override grammar cannot read (``rules=[1,2``,
``program=a;b.txt``) are each one line naming the token and what to type instead; Hydra and argparse would print
4-13 lines of grammar or usage."""

from __future__ import annotations

import difflib
import shlex
from typing import Callable

from .errors import cut

HYDRA_FLAGS = ("-h", "--help", "--hydra-help", "--version", "-c", "--cfg", "--resolve", "-p", "--package", "-r",
               "--run", "-m", "--multirun", "-sc", "--shell-completion", "-cp", "--config-path", "-cn",
               "--config-name", "-cd", "--config-dir", "-i", "--info", "--experimental-rerun")
"""the flags a neurosym command takes (Hydra's); everything else is key=value"""
GROUPS = ("task", "budget", "baseline")


def _choice(word: str, choices: Callable[[str], list[str]]) -> tuple[str, str] | None:
    """(group, option) of the option ``word`` names or nearly names (``random-grd`` -> task, random-grid)."""
    options = {o: g for g in GROUPS for o in choices(g)}
    if word in options:
        return options[word], word
    near = difflib.get_close_matches(word, list(options), n=1, cutoff=0.75)
    return (options[near[0]], near[0]) if near else None


def _override(key: str, value: str, choices: Callable[[str], list[str]]) -> str:
    """``key=value`` as the user most likely meant it: a group's value corrected to its closest option."""
    if key in GROUPS and value not in choices(key):
        near = difflib.get_close_matches(value, choices(key), n=1, cutoff=0.6)
        value = near[0] if near else value
    return f"{key}={value}"


def check_words(args: list[str], flag_values: set[str], keys: dict[str, str],
                choices: Callable[[str], list[str]]) -> str | None:
    """A one-line error for the first argument that is neither a Hydra flag nor an override, else None.
    ``flag_values``: arguments that are a flag's value (``--cfg job``); ``keys``: every key an override may set."""
    skip = set()
    for i, a in enumerate(args):
        nxt = args[i + 1] if i + 1 < len(args) else None
        if i in skip or a in flag_values:
            continue
        if a.startswith("-"):
            flag, eq, value = a.partition("=")
            if flag in HYDRA_FLAGS or flag.startswith("-sc"):
                continue
            key = flag.lstrip("-").replace("_", "-") if flag.lstrip("-").replace("_", "-") in GROUPS else \
                flag.lstrip("-").replace("-", "_")
            if key in keys or key in GROUPS:
                if not eq and nxt is not None and not nxt.startswith("-") and "=" not in nxt:
                    value, eq = nxt, "="
                    skip.add(i + 1)
                if eq:
                    shown = a if a != flag else f"{flag} {value}"
                    return f"{shown}: settings are key=value; did you mean {_override(key, value, choices)}?"
                return f"{flag}: settings are key=value; did you mean {key}=...?"
            near = difflib.get_close_matches(flag, HYDRA_FLAGS, n=1, cutoff=0.8)
            return (f"unknown flag {flag}" + (f"; did you mean {near[0]}?" if near else "") +
                    "; settings are key=value (`neurosym <command> --help` lists them)")
        if "=" in a or a.startswith("~"):
            continue
        found = _choice(a, choices)
        if found:
            return f"{a!r} is not an override; did you mean {found[0]}={found[1]}?"
        if a in keys and nxt is not None and "=" not in nxt and not nxt.startswith("-"):
            return f"{a!r} is not an override; did you mean {_override(a, nxt, choices)}?"
        near = difflib.get_close_matches(a, list(keys), n=1, cutoff=0.75)
        return (f"{a!r} is not an override (key=value)" + (f"; did you mean {near[0]}=...?" if near else "")
                + "; `neurosym <command> --help` lists the keys")
    return None


def _shell(text: str) -> str:
    """``text`` quoted for a POSIX shell, in the plainest form that keeps it verbatim."""
    if "'" not in text:
        return f"'{text}'"
    if not any(c in text for c in "$`!"):  # inside double quotes only these (and " and \\) are special
        return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return shlex.quote(text)


def hydra_quoted(key: str, value: str) -> str | None:
    """``key=value`` quoted so that Hydra reads ``value`` verbatim, and quoted again for a POSIX shell (what to
    type); None when no quoting reads back as ``value``."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    parser = OverridesParser.create()
    forms = [f"'{value}'", f'"{value}"', "'" + value.replace("\\", "\\\\").replace("'", "\\'") + "'"]
    found = []
    for form in forms:
        try:
            o = parser.parse_override(f"{key}={form}")
        except Exception:  # Hydra raises its own exception types for grammar errors
            continue
        if o.value() == value:
            found.append(_shell(f"{key}={form}"))
    return min(found, key=len) if found else None


def _token(key: str, value: str) -> str:
    """The character of ``value`` at which Hydra's grammar stops reading it: the end of the first prefix it
    cannot read (an opening bracket counts until it is closed, so ``[1,2`` names ``[``)."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    parser = OverridesParser.create()
    for i in range(1, min(len(value), SCAN) + 1):  # a parse per prefix: quadratic, so bounded
        try:
            parser.parse_override(f"{key}={value[:i]}")
        except Exception:  # Hydra raises its own exception types for grammar errors
            return repr(value[i - 1])
    return "its end" if len(value) <= SCAN else f"a character after its first {SCAN}"


SCAN = 400
"""characters of a value searched for the one Hydra's grammar stops at"""


def check_grammar(args: list[str], flag_values: set[str], multirun: bool, keys: dict[str, str]) -> str | None:
    """A one-line error for the first override Hydra's grammar cannot read (naming the token and, for a text, the
    quoting that works), or a comma that would make a sweep outside -m; else None. ``keys``: every key an override
    may set, with its declared type (a key it does not know may be a text)."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    from .overrides import number_hint

    parser = OverridesParser.create()
    for a in args:
        if a.startswith("-") or a in flag_values or "=" not in a:
            continue
        key, _, value = a.partition("=")
        text = keys.get(key.lstrip("+~"), "str") in ("str", "Optional[str]")
        try:
            o = parser.parse_override(a)
        except Exception:
            hint = number_hint(key.lstrip("+~"), value, keys)  # a number in other digits: how to write it
            if hint:
                return f"{cut(a)}: {hint}"
            quoted = hydra_quoted(key.lstrip("+~"), value) if text else None
            lists = "; a list is [a,b] with its brackets closed" if value.startswith("[") else ""
            fix = f"; for the text itself quote it: {quoted}" if quoted else ""
            return (f"{cut(a)}: Hydra's override grammar cannot read {cut(repr(value))} at {_token(key, value)}{lists}"
                    f"{cut(fix)}")
        if o.is_sweep_override() and not multirun:
            if "," not in value:
                return f"{a}: {value} is a sweep; add -m to run one job per value"
            hint = number_hint(key.lstrip("+~"), value, keys)  # lam=0,5: a decimal comma
            if hint:
                return f"{cut(a)}: {hint}; a comma makes a sweep (add -m)"
            quoted = hydra_quoted(key.lstrip("+~"), value) if text else None
            return (f"{a}: a comma makes a sweep (add -m) or, in brackets, a list ({key}=[...])"
                    + (f"; for a value with a comma in it quote it: {quoted}" if quoted else ""))
    return None
