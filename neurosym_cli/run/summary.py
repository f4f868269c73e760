"""A program search's summary.json, the other half of its program.txt: one unit. `synth` writes the summary first
and the program last (stages/synth.py), so a program in the run directory has its search's summary beside it; a
program without one (a search stopped between the two writes by an older version, a copy, an edit) is refused by the
verbs that run it and shown without objective terms by show-program."""

from __future__ import annotations

import json
from pathlib import Path

from ..dsl.ast import Program
from ..dsl.printer import to_text
from ..utils.io import ArtifactError
from .layout import SUMMARY


def is_program_summary(rec: object) -> bool:
    """Whether a record is a program search's summary.json: every round with its objective terms and time."""
    rounds = rec.get("rounds") if isinstance(rec, dict) else None
    return isinstance(rounds, list) and bool(rounds) and all(
        isinstance(r, dict) and all(isinstance(r.get(k), (int, float)) and not isinstance(r.get(k), bool)
                                    for k in ("objective", "l1", "degree", "seconds")) for r in rounds)


def summary_beside(program_file: Path) -> Path:
    """Where the summary of the search that wrote ``program_file`` lies."""
    return Path(program_file).parent / SUMMARY


def read_matching(program_file: Path, program: Program) -> tuple[dict | None, str]:
    """(summary, "") when the summary.json beside ``program_file`` is a program search's and records ``program``
    (rules compared, comments aside); else (None, why not, a phrase)."""
    summary = summary_beside(program_file)
    if not summary.is_file():
        return None, f"has no {SUMMARY} beside it"
    try:
        rec = json.loads(summary.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:  # unreadable, not UTF-8, not JSON
        return None, f"has a {SUMMARY} beside it that cannot be read ({type(e).__name__})"
    if not is_program_summary(rec) or not isinstance(rec.get("program"), str):
        return None, f"has a {SUMMARY} beside it that is not of the shape synth writes"
    if rec["program"] != to_text(program):
        return None, f"is not the program its {SUMMARY} records (edited, or written by another search)"
    return rec, ""


def check_synthesized(program_file: Path, program: Program, made_by: str) -> dict:
    """The summary of a synthesized program, or one line: a program and its summary are one unit, and the verbs
    that run a program do not run half of one. ``made_by``: the synth command of this program."""
    rec, why = read_matching(program_file, program)
    if rec is None:
        raise ArtifactError(f"{program_file} {why}: its search did not finish or the file is not synth's; "
                            f"`{made_by} overwrite=true` searches it again (a program of your own goes in with "
                            "program=PATH)")
    return rec
