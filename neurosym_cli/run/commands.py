"""The command lines that make (or make again) an artifact of a run directory: what error messages tell the user to
run (stdlib only). Each comes from the baseline's scheme (``cfg.baseline.command``), which knows its own stages."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..baselines import ORACLE, train_line

if TYPE_CHECKING:
    from ..config import RunConfig


def train_command(cfg: "RunConfig", oracle: bool = False) -> str:
    """The command line that makes the weights ``cfg``'s baseline needs (or the oracle's)."""
    return train_line(cfg, ORACLE) if oracle else cfg.baseline.weights_command(cfg)


def retrain_command(cfg: "RunConfig") -> str:
    """The command line that retrains ``cfg``'s (retrained) baseline."""
    return cfg.baseline.command("retrain", cfg)


def synth_command(cfg: "RunConfig") -> str:
    """The command line that synthesizes the program or tree ``cfg``'s baseline runs under."""
    return cfg.baseline.command("synth", cfg)


def pipeline_command(cfg: "RunConfig") -> str:
    """The command line that makes (or reuses) every artifact of ``cfg``'s run directory and evaluates again."""
    return f"neurosym pipeline task={cfg.task.name} budget={cfg.budget.name} seed={cfg.seed}"
