"""`neurosym rl`: communication decisions as actions (paper appendix D), trained over a grid; rl1 and rl2."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.rl import run_rl


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return run_rl(cfg, info)
