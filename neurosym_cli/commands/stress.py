"""`neurosym stress`: trained baselines evaluated zero-shot at other team sizes and under link failure."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.stress import run_stress


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return run_stress(cfg, info)
