"""`neurosym report`: one table and plot over every training seed of a (task, budget), or of report_dir=PATH (a
directory of seed directories, or one experiment directory): mean over training seeds, with their spread."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.results import report


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return report(cfg)
