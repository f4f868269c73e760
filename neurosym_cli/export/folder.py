"""An export folder on disk: what counts as one, and replacing one without ever touching anything else.

An export is a folder whose manifest.json names the format ``neurosym-export/...`` and lists every file in it
(``__pycache__`` aside, left by running its Python files). Only such a folder, or an empty one, is ever replaced:
a run directory, a user's own folder or an export a user added files to is refused in one line, even with
overwrite=true. The new export is built in a temporary sibling and renamed into place under the parent's lock,
and only if the folder is still what it was when the export began: of two exports into one folder at once, the
one that finishes second says it was discarded instead of silently replacing the other.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

from ..errors import ConfigError, UserError
from ..run.layout import EXPORT_MANIFEST

FORMAT = "neurosym-export/1"
"""manifest.json's ``format``: the marker of an export folder"""

_CACHE = "__pycache__"


def manifest_problem(folder: Path) -> str | None:
    """None when ``folder/manifest.json`` is an export's manifest; else why not, in words."""
    try:
        manifest = json.loads((Path(folder) / EXPORT_MANIFEST).read_text())
    except FileNotFoundError:
        return "it holds no manifest.json"
    except (OSError, ValueError) as e:
        return f"its manifest.json cannot be read ({type(e).__name__})"
    if not isinstance(manifest, dict) or not str(manifest.get("format", "")).startswith("neurosym-export/"):
        return "its manifest.json is not an export's"
    if not isinstance(manifest.get("files"), list):
        return "its manifest.json lists no files"
    return None


def why_not_export(folder: Path) -> str | None:
    """None when ``folder`` is an export neurosym wrote and nothing else; else why not, in words."""
    folder = Path(folder)
    problem = manifest_problem(folder)
    if problem:
        return problem
    listed = set(json.loads((folder / EXPORT_MANIFEST).read_text())["files"])
    dirs = {p for f in listed for p in Path(f).parents if str(p) != "."}
    extra = []
    for here, subdirs, names in os.walk(folder):  # links are not followed: a link is an entry like a file
        rel = Path(here).relative_to(folder)
        subdirs[:] = [d for d in subdirs if d != _CACHE or os.path.islink(os.path.join(here, d))]
        for d in subdirs:
            if rel / d not in dirs or os.path.islink(os.path.join(here, d)):
                extra.append((rel / d).as_posix() + "/")
        subdirs[:] = [d for d in subdirs if rel / d in dirs and not os.path.islink(os.path.join(here, d))]
        extra += [(rel / n).as_posix() for n in names if (rel / n).as_posix() not in listed]
    if extra:
        shown = ", ".join(sorted(extra)[:3]) + (f" and {len(extra) - 3} more" if len(extra) > 3 else "")
        return f"it holds what an export does not write: {shown}"
    return None


def _state(folder: Path) -> object:
    """What is at ``folder`` now: None (nothing), 'empty' (an empty folder), 'other', or an export's stamp (the
    folder's and its manifest's inode and the manifest's mtime: a replaced export has another)."""
    try:
        st = os.lstat(folder)
    except FileNotFoundError:
        return None
    if folder.is_symlink() or not folder.is_dir():
        return "other"
    if not any(folder.iterdir()):
        return "empty"
    try:
        m = os.lstat(folder / EXPORT_MANIFEST)
    except OSError:
        return "other"
    return (st.st_ino, m.st_ino, m.st_mtime_ns)


def claim(folder: Path, *, overwrite: bool) -> object:
    """What ``folder`` holds before an export writes it (to hand to ``publish``); one line when the export must
    not go there: a file or link, a folder that is not an export (whatever overwrite says), an export without
    overwrite=true."""
    folder = Path(folder)
    state = _state(folder)
    if state is None or state == "empty":
        return state
    if folder.is_symlink() or not folder.is_dir():
        raise ConfigError(f"{folder} exists and is not a folder; export.dir= a new folder")
    why = why_not_export(folder)
    if why:
        raise ConfigError(f"{folder} is not an export folder ({why}); an export only ever replaces an export, so "
                          f"not even overwrite=true writes there: export.dir= a new folder")
    if not overwrite:
        raise ConfigError(f"{folder} exists; overwrite=true replaces it (export.check=true checks it)")
    return state


def publish(tmp: Path, folder: Path, claimed: object) -> None:
    """Rename the finished export ``tmp`` to ``folder``, replacing what ``claim`` saw there, only while the
    parent's lock is held and ``folder`` is still what it saw (else one line, and ``tmp`` is left to the
    caller to remove)."""
    from ..utils.lock import run_lock

    folder = Path(folder)
    old = None
    with run_lock(folder.parent):
        if _state(folder) != claimed:
            raise UserError(f"another export wrote {folder} while this one ran: that one is kept and this one "
                            f"is discarded; run it again with overwrite=true to replace it")
        if claimed == "empty":
            folder.rmdir()
        elif claimed is not None:
            old = folder.parent / f".{folder.name}.old-{os.getpid()}"
            os.rename(folder, old)
        os.rename(tmp, folder)  # the folder appears complete or not at all
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
