"""`neurosym export`: a baseline's program and policy as artifacts that run without neurosym; `--check` replays
them in a process that cannot import neurosym."""

from __future__ import annotations

from ..config import RunConfig
from ..stages import RunInfo
from ..stages.export import export


def run(cfg: RunConfig, info: RunInfo) -> dict:
    return export(cfg, info)
