"""`neurosym tune`: select's choice of (lam, K, features) and the retraining's rate by an Optuna study."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.tune import run_tune


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return run_tune(cfg, info)
