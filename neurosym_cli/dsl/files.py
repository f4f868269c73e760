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


def load_program(path: Path, made_by: str) -> Program:
    """Parse a program file; a missing file names the command that makes it, bad text its line and column."""
    path = Path(path)
    if not path.exists():
        raise ArtifactError(f"no program at {path}; create it with `{made_by}`")
    try:
        return parse(path.read_text(), source=str(path))
    except ProgramSyntaxError as e:
        raise ArtifactError(f"malformed program: {e}") from None
