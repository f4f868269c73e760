"""One writer per run directory: an advisory lock (flock) on <dir>/.lock, held while a command writes there.

A second command that would write the same directory (the same model trained twice, or with other settings)
stops at once with one line naming the process that holds it, instead of overwriting its model, history and
manifest. The lock dies with its process (kill -9 included), so a crashed run never leaves a stale lock.
"""

from __future__ import annotations

import os
import shlex
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from ..errors import resource_problem
from .io import ArtifactError, check_inside

try:
    import fcntl
except ImportError:  # pragma: no cover - not on Linux or macOS: no locking, as before
    fcntl = None  # type: ignore[assignment]


class Busy(ArtifactError):
    """Another process holds the directory's lock: it is writing there now (a rerun after it ends resumes or reuses
    its result; `neurosym tune` waits for it)."""


@contextmanager
def run_lock(directory: Path) -> Iterator[None]:
    """Hold ``directory``'s lock for the duration of the block (``Busy`` when another process holds it)."""
    directory = Path(directory)
    check_inside(directory)
    made = [d for d in (directory, *directory.parents) if not d.exists()]  # deepest first
    held = False
    lock = directory / ".lock"
    try:
        directory.mkdir(parents=True, exist_ok=True)
        fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o666)
    except IsADirectoryError:  # the lock's name is taken by a directory (made by hand, or a copy gone wrong)
        raise ArtifactError(f"{lock} is a directory, not the lock file neurosym keeps there; move it away "
                            f"(or `rmdir {shlex.quote(str(lock))}` when empty) and run again") from None
    except OSError as e:
        e.filename = e.filename or str(directory)
        raise ArtifactError(resource_problem(e) or f"cannot write to {directory}: {e.strerror or e}") from None
    try:
        if fcntl is not None:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.pread(fd, 512, 0).decode(errors="replace").strip() or "another process"
                raise Busy(f"{directory} is being written by {holder}; wait for it to finish (a rerun "
                                    f"then resumes or reuses its result), or write elsewhere with runs_root=...") from None
        held = True
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()} ({' '.join(sys.argv)[:200]})".encode(), 0)
        yield
    finally:
        if held:
            _tidy(directory, made)  # before the lock is released: nobody else can be using the directory
        os.close(fd)  # closing releases the lock


def _tidy(directory: Path, made: list[Path]) -> None:
    """A command that stopped before writing anything leaves no trace: the directories this lock made, when they
    hold nothing but the lock file (a failed synth must not leave an empty synth/<tag>/)."""
    if not made or made[0] != directory:
        return
    try:
        if [p.name for p in directory.iterdir()] != [".lock"]:
            return
        (directory / ".lock").unlink()
        for d in made:
            d.rmdir()  # fails (and stops) on the first one that is not empty
    except OSError:
        pass
