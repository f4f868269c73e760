"""`neurosym figures`: the paper's figures (1, 3a, 3b, 4, 5) drawn from a run directory's models and program."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.render import make_figures


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return make_figures(cfg, info)
