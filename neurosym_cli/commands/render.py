"""`neurosym render`: one evaluation episode of one baseline, from its run directory, as an animation and a
picture (no retraining)."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.render import render_episode


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return render_episode(cfg, info)
