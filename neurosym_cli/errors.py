"""The errors every layer raises for bad input (stdlib only): reported by the commands as one line, no traceback."""

from __future__ import annotations

import dataclasses
import math


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
