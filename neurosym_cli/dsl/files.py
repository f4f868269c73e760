"""Program files: the text form with '#' comment lines in front, written atomically and read back by our parser."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

from ..utils.io import ArtifactError, write_text
from .ast import Program
from .parser import ProgramSyntaxError, parse


def save_program(path: Path, text: str, header: Sequence[str]) -> None:
    """Program text with '#' comment lines in front (the parser skips them)."""
    write_text(Path(path), "".join(f"# {h}\n" for h in header) + text)


def load_program(path: Path, made_by: str | None = None) -> Program:
    """Parse a program file; errors are one line: a missing file names the command that makes it (``made_by``, for
    a synthesized program; None for a file the user gave), bad text its line and column."""
    path = Path(path)
    again = f"; `{made_by} overwrite=true` searches it again" if made_by else ""
    if not path.exists():
        raise ArtifactError(f"no program at {path}" + (f"; create it with `{made_by}`" if made_by else ""))
    if not path.is_file():
        raise ArtifactError(f"{path} is not a file; program= takes the path of a program text file")
    try:
        data = path.read_bytes()
    except OSError as e:
        raise ArtifactError(f"cannot read {path}: {e.strerror or e}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        line = data[: e.start].count(b"\n") + 1
        raise ArtifactError(f"malformed program: {path}:{line}: not UTF-8 text (byte {e.start}){again}") from None
    try:
        return parse(text, source=str(path))
    except ProgramSyntaxError as e:
        raise ArtifactError(f"malformed program: {e}{again}") from None
