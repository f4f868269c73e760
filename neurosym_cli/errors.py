"""The errors every layer raises for bad input (stdlib only): reported by the commands as one line, no traceback."""

from __future__ import annotations


class UserError(Exception):
    """Bad input from the user (config, missing or corrupt artifact): reported as one line, no traceback."""


class ConfigError(UserError, ValueError):
    """A configuration value is out of range; the message names the key and the fix."""


def check(ok: bool, msg: str) -> None:
    """Raise ConfigError(msg) unless ``ok`` (the range checks of every schema's ``__post_init__``)."""
    if not ok:
        raise ConfigError(msg)
