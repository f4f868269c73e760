"""`neurosym train`: train the oracle transformer (or a baseline's own model) into a resumable checkpoint."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.train import train


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return train(cfg, info)
