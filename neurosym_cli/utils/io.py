"""Atomic file writes and safe reads of plain-text artifacts (stdlib only: usable without torch)."""

from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from pathlib import Path
from typing import Any, Mapping, Sequence

from ..config import UserError
from ..errors import lies_under


class ArtifactError(UserError):
    """A required artifact is missing or unreadable; the message says which command makes it."""


def _file_mode() -> int:
    """What open() would give a new file under the process's umask (mkstemp makes 0600 whatever the umask)."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


_MODE = _file_mode()

_ROOTS: list[Path] = []
"""where a command may write (``confine``): its runs root, and the output directories the user named"""


def confine(roots: Sequence[str | Path]) -> None:
    """Let this process write only under ``roots`` (set by the command wrapper, commands/_run.py); empty: anywhere
    (the Python API, tests)."""
    _ROOTS[:] = [Path(r).expanduser().resolve() for r in roots]


def check_inside(path: Path) -> None:
    """Refuse to write ``path`` outside the confined roots (every artifact write and run directory goes through
    here): a name that slipped past the schema's checks must not write elsewhere on the machine."""
    if not _ROOTS:
        return
    if not any(lies_under(path, r) for r in _ROOTS):
        raise ArtifactError(f"refusing to write {Path(path).resolve()}: it lies outside the runs root {_ROOTS[0]}")


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``path`` so that a reader sees the old file or the new one, never a part (temp file, fsync, rename)."""
    check_inside(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as e:
        raise ArtifactError(f"cannot write {path}: {e.strerror or e}") from None
    try:
        os.fchmod(fd, _MODE)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_text(path: Path, text: str) -> None:
    atomic_write_bytes(path, text.encode())


def write_json(path: Path, obj: Any) -> None:
    write_text(path, json.dumps(obj, indent=2, sort_keys=False) + "\n")


def write_csv(path: Path, rows: Sequence[Mapping[str, Any]]) -> None:
    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    write_text(path, buf.getvalue())


def read_json(path: Path) -> Any:
    try:
        return json.loads(Path(path).read_text())
    except (OSError, ValueError) as e:  # unreadable, not UTF-8, or not JSON
        raise ArtifactError(f"cannot read {path}: {e}") from None
