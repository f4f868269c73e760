"""`neurosym select`: the paper's model selection by validation over a grid of (lam, K, features)."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.select import run_selection


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return run_selection(cfg, info)
