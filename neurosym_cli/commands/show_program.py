"""`neurosym show-program`: pretty-print a program in the paper's notation with a plain-language reading.

Reads text only (the program file and its summary.json): no torch import, so it answers in a fraction of a
second.
"""

from __future__ import annotations

import json
from pathlib import Path

from rich.panel import Panel
from rich.table import Table

from .. import paths
from ..config import RunConfig
from ..dsl.ast import Program
from ..dsl.printer import describe, rule_text
from ..utils.console import console
from ..utils.io import load_program
from ._run import Context


def render(program: Program, rounds: list[dict] | None, lam: float | None, title: str = "program") -> None:
    """Print each rule in the paper's notation beside its reading, and the objective terms when known."""
    for r, rules in enumerate(program.rounds):
        t = Table(show_header=True, header_style="bold", expand=False)
        t.add_column("#", justify="right")
        t.add_column("rule (paper notation)")
        t.add_column("reading")
        for k, rule in enumerate(rules, start=1):
            t.add_row(str(k), rule_text(rule), describe(rule))
        info = rounds[r] if rounds and r < len(rounds) else None
        sub = ""
        if info is not None and lam is not None:
            sub = (f"objective {info['objective']:.4f} = L1 action error {info['l1']:.4f} + {lam:g} x degree "
                   f"{info['degree']:.3f}")
        name = f"{title}, round {r + 1}" if program.n_rounds > 1 else title
        console.print(Panel(t, title=name, subtitle=sub or None, expand=False))


def run(cfg: RunConfig, ctx: Context) -> dict:
    path = paths.program_file(cfg)
    program = load_program(path, paths.synth_command(cfg))
    summary = path.parent / "summary.json"
    rounds, lam = None, None
    if summary.exists():
        try:
            meta = json.loads(summary.read_text())
            rounds, lam = meta.get("rounds"), meta.get("lam")
        except (OSError, ValueError):
            pass
    render(program, rounds, lam, title=str(Path(path)))
    return {"program": str(path)}
