"""Run tracking: the metrics of every training and search step, beyond the CSV files the stages always write
(history.csv, trace.csv). ``logger=tensorboard`` adds TensorBoard event files under <exp_dir>/tensorboard/<run>,
so `tensorboard --logdir outputs` shows every run; no account or network is needed."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

from ..config import UserError
from .io import check_inside


class Tracker:
    """A sink for per-step scalars; the CSV files are the stages' own, so the plain tracker does nothing more."""

    def log(self, step: int, metrics: Mapping[str, float]) -> None:
        """Record ``metrics`` (name -> value) at ``step`` (an optimizer step or an MCMC proposal)."""

    def close(self) -> None:
        """Flush and release the sink."""

    def __enter__(self) -> "Tracker":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class TensorBoardTracker(Tracker):
    """Scalars into TensorBoard event files; on resume, events after ``start`` are dropped (purge_step), so a
    resumed run's curve has no doubled steps."""

    def __init__(self, logdir: Path, start: int = 0):
        try:
            from torch.utils.tensorboard import SummaryWriter
        except ImportError:
            raise UserError("logger=tensorboard needs the tensorboard extra: pip install -e '.[tensorboard]' in the "
                            "neurosym checkout (or pip install tensorboard; or logger=csv)") from None
        check_inside(logdir)
        logdir.mkdir(parents=True, exist_ok=True)
        if not start:  # a run that starts over (overwrite=true, a new search) starts a new curve
            for old in logdir.glob("events.out.tfevents.*"):
                old.unlink()
        self.writer = SummaryWriter(str(logdir), purge_step=start + 1 if start else None)

    def log(self, step: int, metrics: Mapping[str, float]) -> None:
        for name, value in metrics.items():
            self.writer.add_scalar(name, float(value), step)

    def close(self) -> None:
        self.writer.close()


def open_tracker(logger: str, logdir: Path, start: int = 0) -> Tracker:
    """The tracker of ``logger=<logger>`` for one run, writing under ``logdir``; ``start``: the step resumed from."""
    return TensorBoardTracker(logdir, start) if logger == "tensorboard" else Tracker()
