"""`neurosym retrain`: the oracle fine-tuned under the synthesized program or tree (paper section 3.5)."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.train import retrain


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return retrain(cfg, info)
