"""Persistent defaults of the console script (stdlib and PyYAML only): the task and budget a command runs with
when its command line names none, so they need not be retyped on every command.

Where they come from, first found wins: the command line (``task=``, ``budget=``), the environment
(``NEUROSYM_TASK``, ``NEUROSYM_BUDGET``), then a project file in the working directory (``neurosym.yaml`` or
``.neurosym.yaml``, holding ``task: <name>`` and/or ``budget: <name>``), then each command's own config
(``conf/<command>.yaml``: random-cross, quick). Every command's first log line names the values in effect and where
a default came from (``commands/_run.py``)."""

from __future__ import annotations

import os
from pathlib import Path

KEYS = {"task": "NEUROSYM_TASK", "budget": "NEUROSYM_BUDGET"}
"""the config groups that take a persistent default -> their environment variable"""
FILES = ("neurosym.yaml", ".neurosym.yaml")
"""project files looked for in the working directory"""
MAX_BYTES = 1_000_000
"""the largest project file read: it holds two names; anything near this size is another file under its name"""
SOURCES_ENV = "NEUROSYM_DEFAULTS_FROM"
"""set by the console script for the command's process: 'task=<where>;budget=<where>' of the defaults it applied"""


class DefaultsError(ValueError):
    """A project file that cannot be read or holds what it cannot (one line, naming the file)."""


def project_file(cwd: Path | None = None) -> Path | None:
    """The project file of the working directory, or None; two of them are an error (which one would win?)."""
    found = [p for p in ((cwd or Path.cwd()) / f for f in FILES) if p.is_file()]
    if len(found) > 1:
        raise DefaultsError(f"both {found[0]} and {found[1]} hold neurosym defaults; keep one")
    return found[0] if found else None


def read_project_file(path: Path) -> dict[str, str]:
    """``{"task": ..., "budget": ...}`` of a project file (either may be absent); one line for anything else."""
    import yaml

    try:
        size = path.stat().st_size
    except OSError as e:
        raise DefaultsError(f"cannot read the defaults file {path} ({e.strerror or e})") from None
    if size > MAX_BYTES:  # YAML of that size takes minutes and gigabytes to parse, for two names
        raise DefaultsError(f"the defaults file {path} holds {size / 1e6:.1f} MB, more than the "
                            f"{MAX_BYTES // 1000} kB a defaults file may; it holds lines like `task: random-grid` and "
                            "`budget: tiny` (is it the file you meant?)")
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as e:
        first = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise DefaultsError(f"cannot read the defaults file {path} ({first}); it holds lines like `task: random-grid` "
                            "and `budget: tiny`") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise DefaultsError(f"{path} must map keys to values, like `task: random-grid` and `budget: tiny`")
    unknown = [str(k) for k in data if k not in KEYS]
    if unknown:
        raise DefaultsError(f"{path}: unknown key {unknown[0]!r}; it may set {' and '.join(KEYS)} (anything else goes "
                            "on the command line)")
    bad = [k for k, v in data.items() if not isinstance(v, str) or not v.strip()]
    if bad:
        raise DefaultsError(f"{path}: {bad[0]} must be a name, like `{bad[0]}: {'random-grid' if bad[0] == 'task' else 'tiny'}`")
    return {k: v.strip() for k, v in data.items()}


def named(args: list[str], key: str) -> bool:
    """Whether the command line picks ``key``'s config group itself (``task=...``, ``+task=...``, ``~task``)."""
    return any(a.partition("=")[0].lstrip("+~") == key for a in args if not a.startswith("-"))


def apply(args: list[str], cwd: Path | None = None) -> tuple[list[str], dict[str, str]]:
    """``args`` with ``task=``/``budget=`` added for the groups the command line leaves out and a default names;
    returns (args, {key: where the default came from}). Raises DefaultsError for a bad project file."""
    path = project_file(cwd)
    from_file = read_project_file(path) if path else {}
    added, sources = [], {}
    for key, env in KEYS.items():
        if named(args, key):
            continue
        if os.environ.get(env, "").strip():
            added.append(f"{key}={os.environ[env].strip()}")
            sources[key] = env
        elif key in from_file:
            added.append(f"{key}={from_file[key]}")
            sources[key] = str(path)
    return added + list(args), sources


def describe(sources: dict[str, str]) -> str:
    """``task=...;budget=...`` for SOURCES_ENV."""
    return ";".join(f"{k}={v}" for k, v in sources.items())


def sources_in_effect() -> dict[str, str]:
    """What the console script recorded in SOURCES_ENV for this process: {key: where its default came from}."""
    out = {}
    for part in os.environ.get(SOURCES_ENV, "").split(";"):
        key, sep, where = part.partition("=")
        if sep and key in KEYS:
            out[key] = where
    return out
