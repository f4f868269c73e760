"""Atomic file writes and safe reads of plain-text artifacts (stdlib only: usable without torch)."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import tempfile
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping, Sequence

from ..config import UserError
from ..errors import cut, lies_under, resource_problem


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


def confined() -> list[Path]:
    """The roots this process may write under (``confine``); empty: anywhere."""
    return list(_ROOTS)


def check_inside(path: Path) -> None:
    """Refuse to write ``path`` outside the confined roots (every artifact write and run directory goes through
    here): a name that slipped past the schema's checks must not write elsewhere on the machine."""
    if not _ROOTS:
        return
    if not any(lies_under(path, r) for r in _ROOTS):
        raise ArtifactError(f"refusing to write {Path(path).resolve()}: it lies outside the runs root {_ROOTS[0]}")


def _write_error(path: Path, e: OSError) -> ArtifactError:
    e.filename = e.filename or str(path)  # a failed write() names no file: the artifact it was for
    return ArtifactError(resource_problem(e) or f"cannot write {path}: {e.strerror or e}")


@contextlib.contextmanager
def atomic_file(path: Path) -> Iterator[Path]:
    """A temporary path beside ``path`` to write; renamed to ``path`` when the block ends without error, removed
    when it fails (a full disk, Ctrl-C): a reader sees the old file or the new one, never a part. Errors of the
    machine (no space, read-only) are one line (``errors.resource_problem``)."""
    path = Path(path)
    check_inside(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=f".tmp{path.suffix}")
        os.fchmod(fd, _MODE)
        os.close(fd)
    except OSError as e:
        raise _write_error(path, e) from None
    tmp = Path(name)
    try:
        yield tmp
        with open(tmp, "rb+") as f:  # what the block wrote reaches the disk before it takes the name
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as e:
        raise _write_error(path, e) from None
    finally:
        if tmp.exists():
            tmp.unlink()


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``path`` so that a reader sees the old file or the new one, never a part (temp file, fsync, rename)."""
    with atomic_file(path) as tmp:
        tmp.write_bytes(data)


def write_together(files: Mapping[Path, bytes]) -> None:
    """Write the files of one artifact (metrics.json and metrics.csv, a checkpoint and its history) all or none:
    each goes to its temp file first and only then are they renamed, so a full disk leaves every one as it was."""
    with contextlib.ExitStack() as stack:
        tmps = {path: stack.enter_context(atomic_file(path)) for path in files}
        for path, tmp in tmps.items():
            tmp.write_bytes(files[path])


def json_bytes(obj: Any, *, indent: int = 2, sort_keys: bool = False) -> bytes:
    return (json.dumps(obj, indent=indent, sort_keys=sort_keys) + "\n").encode()


def csv_bytes(rows: Sequence[Mapping[str, Any]]) -> bytes:
    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    return buf.getvalue().encode()


def write_text(path: Path, text: str) -> None:
    atomic_write_bytes(path, text.encode())


def write_json(path: Path, obj: Any, *, indent: int = 2, sort_keys: bool = False) -> None:
    """``obj`` as JSON at ``path``, atomically (a temp file of its own beside it: concurrent writers never share
    one); ``indent`` and ``sort_keys`` as json.dumps takes them."""
    atomic_write_bytes(path, json_bytes(obj, indent=indent, sort_keys=sort_keys))


def write_csv(path: Path, rows: Sequence[Mapping[str, Any]]) -> None:
    atomic_write_bytes(path, csv_bytes(rows))


Shape = Mapping[str, "type | tuple[type, ...]"] | Callable[[Any], bool]
"""what a JSON record must be: an object with these fields of these types, or a test of the whole record"""


def read_json(path: Path, remake: str | None = None, shape: Shape | None = None) -> Any:
    """A JSON artifact; unreadable, not UTF-8, not JSON or not of ``shape`` is one ArtifactError that names
    ``remake``, the command that writes it again (a reader never runs on a record of another shape)."""
    again = f"; delete it and run `{remake}`, which writes it again" if remake else ""
    try:
        obj = json.loads(Path(path).read_text())
    except (OSError, ValueError) as e:  # unreadable, not UTF-8, or not JSON
        raise ArtifactError(f"cannot read {path}: {cut(e)}{again}") from None
    if shape is None:
        return obj
    if callable(shape):
        if not shape(obj):
            raise ArtifactError(f"{path} is not a record of the shape neurosym writes{again}")
        return obj
    if not isinstance(obj, dict):
        raise ArtifactError(f"{path} holds a JSON {type(obj).__name__}, not the object neurosym writes{again}")
    for key, typ in shape.items():
        if not isinstance(obj.get(key), typ) or isinstance(obj.get(key), bool) and bool not in _types(typ):
            raise ArtifactError(f"{path}: {key!r} is missing or of another type than neurosym writes{again}")
    return obj


def _types(typ: "type | tuple[type, ...]") -> tuple[type, ...]:
    return typ if isinstance(typ, tuple) else (typ,)
