"""The errors every layer raises for bad input (stdlib only): reported by the commands as one line, no traceback."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path


class UserError(Exception):
    """Bad input from the user (config, missing or corrupt artifact): reported as one line, no traceback."""


class ConfigError(UserError, ValueError):
    """A configuration value is out of range; the message names the key and the fix."""


def check(ok: bool, msg: str) -> None:
    """Raise ConfigError(msg) unless ``ok`` (the range checks of every schema's ``__post_init__``)."""
    if not ok:
        raise ConfigError(msg)


def check_finite(section: object, prefix: str = "") -> None:
    """Refuse nan and inf in every float field of a schema: no comparison in a range check catches inf, and a
    non-finite value trains, searches and reports NaN as if it were a result."""
    for f in dataclasses.fields(section):  # type: ignore[arg-type]
        v = getattr(section, f.name)
        if isinstance(v, float) and not math.isfinite(v):
            raise ConfigError(f"{prefix}{f.name} must be a finite number, got {v}")


def lies_under(path: str | Path, root: str | Path) -> bool:
    """Whether ``path`` lies in ``root`` once both are absolute and normalized (``..`` and links resolved)."""
    p, r = Path(path).expanduser().resolve(), Path(root).expanduser().resolve()
    return p == r or r in p.parents


def name_problem(value: str) -> str | None:
    """Why ``value`` cannot be one component of a path under the runs root (task and budget names, tags), or None:
    a separator or ``..`` would put the run directory elsewhere, an empty name would merge it with its parent."""
    if not value:
        return "is empty"
    if value in (".", ".."):
        return f"is {value!r}"
    bad = [c for c in ("/", "\\", "\0") if c in value]
    return f"contains {bad[0]!r} (a path separator)" if bad else None


def check_name(value: str, key: str) -> None:
    """Refuse a name that would not be one directory under the runs root (``name_problem``)."""
    why = name_problem(value)
    if why:
        raise ConfigError(f"{key}={value!r} {why}; it names a directory under runs_root, so use letters, digits, "
                          "'-', '_' or '.'")
