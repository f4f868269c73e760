"""`neurosym eval`: the evaluation protocol for one baseline; prints a table of every baseline evaluated so far in
the run directory (in a sweep, only its plot is refreshed)."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.evaluate import evaluate_baseline
from ..stages.results import print_table, write_figure


def run(cfg: RunConfig, info: RunInfo) -> dict:
    summary = evaluate_baseline(cfg, info)
    if info.multirun:
        if cfg.plots:
            write_figure(cfg)
    else:
        print_table(cfg)
    return summary
