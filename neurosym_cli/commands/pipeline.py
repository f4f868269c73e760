"""`neurosym pipeline`: every stage for every listed baseline (train, synth, retrain, eval), then the table."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.pipeline import run_pipeline


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return run_pipeline(cfg, info)
