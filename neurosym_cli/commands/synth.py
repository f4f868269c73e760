"""`neurosym synth`: a communication program by MCMC (paper sections 3.2-3.4), or a decision tree (dt)."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.synth import synthesize


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return synthesize(cfg, info)
