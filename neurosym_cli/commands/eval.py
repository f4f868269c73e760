"""`neurosym eval`: the evaluation protocol for one baseline; prints a table of every baseline evaluated so far in
the run directory (in a sweep, only its plot is refreshed)."""

from __future__ import annotations

from pathlib import Path

from ..config import RunConfig
from ..run import RunDir
from ..stages import RunInfo
from ..stages.evaluate import evaluate_baseline
from ..stages.results import print_table, write_figure


def run(cfg: RunConfig, info: RunInfo) -> dict:
    def table() -> list[Path]:
        """The table of every baseline evaluated here (in a sweep, only its plot); the figures it drew."""
        if not info.multirun:
            print_table(cfg)
        elif cfg.plots:
            write_figure(cfg)
        return [RunDir(cfg).figure2_file, RunDir(cfg).curves_file] if cfg.plots else []

    return evaluate_baseline(cfg, info, then=table)
