"""`neurosym show-program`: a program in the paper's notation with a plain-language reading (no torch import)."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.show import show_program


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return show_program(cfg)
