"""The errors every layer raises for bad input (stdlib only): reported by the commands as one line, no traceback."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Iterable


class UserError(Exception):
    """Bad input from the user (config, missing or corrupt artifact): reported as one line, no traceback."""


class ConfigError(UserError, ValueError):
    """A configuration value is out of range; the message names the key and the fix."""


EXIT_CONFIG = 2
"""the exit status of bad configuration (a value out of range, a key or grid that cannot run), wherever it is
found: before Hydra (the console script's checks), in a schema, or in a stage (docs/extending.md: `ConfigError`)"""
EXIT_FAILED = 1
"""the exit status of every other failure: a missing or corrupt artifact, a full disk, a failed sweep job"""


def exit_status(e: BaseException) -> int:
    """The exit status of a command that stopped on ``e``: ``EXIT_CONFIG`` for a configuration error, else
    ``EXIT_FAILED`` (so that `rules=0` exits as `rules=abc` does)."""
    return EXIT_CONFIG if isinstance(e, ConfigError) else EXIT_FAILED


def did_you_mean(word: str, known: Iterable[str]) -> str:
    """'; did you mean 'x'?' for the nearest of ``known`` to a mistyped ``word`` (difflib's ratio >= 0.6), or ''."""
    import difflib

    near = difflib.get_close_matches(word, list(known), n=1, cutoff=0.6)
    return f"; did you mean {near[0]!r}?" if near else ""


def unknown_command(cmd: str, known: Iterable[str]) -> str:
    """The one line for a command that is not one of ``known``: the nearest, then every command."""
    known = list(known)
    near = did_you_mean(cmd, known)
    return f"unknown command {cut(cmd)!r}{near}{' ' if near else '; '}choose one of: {', '.join(known)}"


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


NAME_MAX = 100
"""the longest task, budget or tag name (one directory under the runs root)"""


def name_problem(value: str) -> str | None:
    """Why ``value`` cannot be one component of a path under the runs root (task and budget names, tags), or None:
    a separator or ``..`` would put the run directory elsewhere, an empty name would merge it with its parent."""
    if not value:
        return "is empty"
    if value in (".", ".."):
        return f"is {value!r}"
    if len(value) > NAME_MAX:  # file systems take 255 bytes a name; a run directory's name carries suffixes
        return f"is {len(value):,} characters long (at most {NAME_MAX})"
    bad = [c for c in ("/", "\\", "\0") if c in value]
    return f"contains {bad[0]!r} (a path separator)" if bad else None


def check_name(value: str, key: str) -> None:
    """Refuse a name that would not be one directory under the runs root (``name_problem``)."""
    why = name_problem(value)
    if why:
        raise ConfigError(f"{key}={cut(repr(value))} {why}; it names a directory under runs_root, so use letters, "
                          "digits, '-', '_' or '.'")


LONGEST = 200
"""the most characters of one value a message quotes (a 20,000-character value is cut, its length said)"""


def cut(value: object, limit: int = LONGEST) -> str:
    """``value`` as text, or its start and its length when it is longer than ``limit`` characters."""
    text = str(value)
    return text if len(text) <= limit else f"{text[:limit // 2]}... ({len(text):,} characters)"


def cut_words(msg: str, limit: int = LONGEST) -> str:
    """A message with every word (a run of non-space characters) longer than ``limit`` cut (``cut``): what the
    error edge prints, whoever wrote the message."""
    return " ".join(cut(w, limit) for w in msg.split(" ")) if len(msg) > limit else msg


def resource_problem(e: BaseException) -> str | None:
    """The one line for an error of the machine rather than of neurosym: memory exhausted, a disk that is full or
    read-only, a name too long for the file system; None for any other error (a bug: its traceback is kept)."""
    import errno

    text = str(e).splitlines()[0] if str(e) else type(e).__name__
    if isinstance(e, MemoryError) or (isinstance(e, RuntimeError) and (
            "can't allocate memory" in text or "out of memory" in text.lower())):
        import re

        size = re.search(r"allocate (\d+) bytes", text)
        what = f"it asked for {int(size.group(1)) / 2**30:.1f} GiB more" if size else cut(text, 120)
        return (f"out of memory ({what}); a smaller team (the task's agents) or fewer rollouts at once "
                "(budget.batch_rollouts, task.eval_episodes), or a machine with more memory")
    if not isinstance(e, OSError):
        return None
    where = f" {cut(e.filename)}" if e.filename else ""
    if e.errno in (errno.ENOSPC, errno.EDQUOT):
        return (f"no space left on the disk of{where or ' the runs directory'}; free some, or point runs_root=... "
                "at another disk, then run the same command again (files are written whole or not at all: what "
                "was saved before is intact)")
    if e.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
        return (f"cannot write{where}: {e.strerror} (a read-only or archived directory); point runs_root=... (or "
                "NEUROSYM_RUNS) at a writable directory")
    if e.errno == errno.ENAMETOOLONG:
        return f"a file name is too long for the file system{where}; use shorter names"
    return None
