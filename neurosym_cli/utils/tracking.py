"""Run tracking: the metrics of every training and search step, beyond the CSV files the stages always write
(history.csv, trace.csv). ``logger=`` names the trackers, several joined by ``+`` (``logger=tensorboard+mlflow``):

    csv          nothing more (the CSV files are always written)
    tensorboard  event files under <exp_dir>/tensorboard/<run> (`tensorboard --logdir outputs`)
    mlflow       one MLflow run per tracked run, in MLFLOW_TRACKING_URI's store or, by default, a SQLite store
                 under the runs root (utils/mlflow_tracking.py)
    wandb        one Weights & Biases run per tracked run, offline under the runs root unless an API key is set
                 (utils/wandb_tracking.py)

A tracked run is one stage of one baseline of one (task, budget, seed): training, a program search, an evaluation
(``TrackedRun``). None of them needs an account or a network by default."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import logging

from ..errors import ConfigError, UserError, cut

log = logging.getLogger("neurosym")  # utils/console's, without importing rich into the config's checks

EXTRAS = {"tensorboard": "tensorboard", "mlflow": "mlflow-skinny sqlalchemy alembic", "wandb": "wandb"}
"""tracker -> what pip installs for it outside a checkout (its extra of pyproject.toml has the same name)"""


def logger_problem(logger: object) -> str | None:
    """Why ``logger=<logger>`` names no trackers (one line naming the choices), or None when it does."""
    names = logger.split("+") if isinstance(logger, str) else [None]
    if all(n in LOGGERS for n in names):
        return None
    return (f"logger={cut(repr(logger))}: choose {', '.join(LOGGERS[:-1])} or {LOGGERS[-1]}, several joined by + "
            "(logger=tensorboard+mlflow); csv is always written")


def trackers(logger: str) -> tuple[str, ...]:
    """The trackers ``logger=`` names beyond csv, in order, each once (ConfigError for another name)."""
    why = logger_problem(logger)
    if why:
        raise ConfigError(why)
    return tuple(dict.fromkeys(n for n in logger.split("+") if n != "csv"))


def missing(tracker: str) -> UserError:
    """The one line for a tracker whose package is not installed: the extra that installs it."""
    return UserError(f"logger={tracker} needs the {tracker} extra: pip install -e '.[{tracker}]' in the neurosym "
                     f"checkout (or pip install {EXTRAS[tracker]}; or logger=csv)")


def flatten(record: Mapping[str, Any], prefix: str = "") -> dict[str, str | int | float | bool]:
    """A nested config record as ``{"optim.lr": 0.001, ...}``: numbers, words and flags as they are, lists and
    None as their JSON text."""
    import json

    out: dict[str, str | int | float | bool] = {}
    for k, v in record.items():
        if isinstance(v, Mapping):
            out.update(flatten(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v if isinstance(v, (str, int, float, bool)) else json.dumps(v)
    return out


@dataclass(frozen=True)
class TrackedRun:
    """Who one tracked run is and where its trackers write."""

    key: str
    """unique under the runs root and stable across resumes: <task dir>/<budget>/seed<S>/<run>, e.g.
    random-grid/tiny/seed0/train-oracle (its tensorboard folder's path under the runs root)"""
    tags: Mapping[str, str]
    """task, budget, baseline (the evaluation label), scheme, seed, stage"""
    params: Mapping[str, str | int | float | bool] = field(default_factory=dict)
    """the config it ran under, flattened (``flatten``)"""
    tensorboard: Path = Path("tensorboard")
    """the folder of its TensorBoard event files"""
    store: Path = Path("outputs")
    """the runs root: the local MLflow and W&B stores lie in <store>/mlflow and <store>/wandb"""
    start: int = 0
    """the step resumed from; 0: a run that starts over, which replaces the one of the same key"""

    @property
    def group(self) -> str:
        """What its runs share: one baseline of one (task, budget, training seed),
        <task dir>/<budget>/seed<S>/<baseline> (its train, synth, retrain and eval runs; W&B's group, MLflow's parent run)."""
        return f"{self.key.rsplit('/', 1)[0]}/{self.tags.get('baseline', '')}"


class Tracker:
    """A sink for one tracked run; the CSV files are the stages' own, so the plain tracker does nothing more."""

    def log(self, step: int, metrics: Mapping[str, float]) -> None:
        """Record ``metrics`` (name -> value) at ``step`` (an optimizer step or an MCMC proposal)."""

    def summary(self, metrics: Mapping[str, float]) -> None:
        """Record the run's final numbers (name -> value), e.g. an evaluation's mean loss."""

    def artifact(self, path: Path, folder: str = "") -> None:
        """Keep a copy of the file ``path`` with the run (under ``folder``), e.g. program.txt or a figure."""

    def close(self, failed: bool = False) -> None:
        """Flush and release the sink; ``failed``: the stage stopped on an error."""

    def __enter__(self) -> "Tracker":
        return self

    def __exit__(self, kind, *exc) -> None:
        self.close(failed=kind is not None)


class TensorBoardTracker(Tracker):
    """Scalars into TensorBoard event files, made at the first step (an evaluation writes none); on resume, events
    after ``start`` are dropped (purge_step), so a resumed run's curve has no doubled steps."""

    def __init__(self, logdir: Path, start: int = 0):
        try:
            from torch.utils.tensorboard import SummaryWriter
        except ImportError:
            raise missing("tensorboard") from None
        self.make, self.logdir, self.start, self.writer = SummaryWriter, logdir, start, None

    def log(self, step: int, metrics: Mapping[str, float]) -> None:
        if self.writer is None:
            from .io import check_inside

            check_inside(self.logdir)
            self.logdir.mkdir(parents=True, exist_ok=True)
            if not self.start:  # a run that starts over (overwrite=true, a new search) starts a new curve
                for old in self.logdir.glob("events.out.tfevents.*"):
                    old.unlink()
            self.writer = self.make(str(self.logdir), purge_step=self.start + 1 if self.start else None)
        for name, value in metrics.items():
            self.writer.add_scalar(name, float(value), step)

    def close(self, failed: bool = False) -> None:
        if self.writer is not None:
            self.writer.close()


class Trackers(Tracker):
    """Several trackers as one. A tracker that fails after it opened (a store gone, a full disk) is dropped with
    one warning: the stage goes on, its CSV files hold every number."""

    def __init__(self, sinks: Mapping[str, Tracker]):
        self.sinks = dict(sinks)

    def _each(self, call: str, *args, **kwargs) -> None:
        for name, sink in list(self.sinks.items()):
            try:
                getattr(sink, call)(*args, **kwargs)
            except Exception as e:  # a side channel: the stage's own files are written regardless
                del self.sinks[name]
                log.warning("logger=%s stopped tracking this run (%s: %s); the run goes on, its CSV and JSON "
                            "files hold every number", name, type(e).__name__, cut(str(e).splitlines()[0] if
                                                                                   str(e) else "", 300))

    def log(self, step: int, metrics: Mapping[str, float]) -> None:
        self._each("log", step, metrics)

    def summary(self, metrics: Mapping[str, float]) -> None:
        self._each("summary", metrics)

    def artifact(self, path: Path, folder: str = "") -> None:
        if Path(path).is_file():
            self._each("artifact", Path(path), folder)

    def close(self, failed: bool = False) -> None:
        self._each("close", failed)


def _tensorboard(run: TrackedRun) -> Tracker:
    return TensorBoardTracker(run.tensorboard, run.start)


def _mlflow(run: TrackedRun) -> Tracker:
    from .mlflow_tracking import MLflowTracker

    return MLflowTracker(run)


def _wandb(run: TrackedRun) -> Tracker:
    from .wandb_tracking import WandbTracker

    return WandbTracker(run)


OPENERS = {"tensorboard": _tensorboard, "mlflow": _mlflow, "wandb": _wandb}
"""tracker -> how it opens for one run (its package imported only then)"""

FILES = ("mlflow", "wandb")
"""the trackers that keep files (artifacts); TensorBoard keeps scalars only"""

LOGGERS = ("csv", *OPENERS)
"""the choices of ``logger=``, joined by + to combine them"""


def open_tracker(logger: str, run: TrackedRun) -> Tracker:
    """The trackers of ``logger=<logger>`` for ``run``, opened (a missing package or an unreachable store: one
    line, before the stage does any work)."""
    sinks: dict[str, Tracker] = {}
    try:
        for name in trackers(logger):
            sinks[name] = OPENERS[name](run)
    except BaseException:
        Trackers(sinks).close(failed=True)
        raise
    return Trackers(sinks)
