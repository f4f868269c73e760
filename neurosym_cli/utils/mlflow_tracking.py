"""logger=mlflow: one MLflow run per tracked run (utils/tracking.TrackedRun), with its identity as tags, its config
as parameters, every step's metrics, its summary and its files as artifacts.

The store is MLFLOW_TRACKING_URI's when set (a server, a database, ...); else a SQLite store under the runs root,
<runs_root>/mlflow/mlflow.db with the artifacts in <runs_root>/mlflow/artifacts: no server, no network
(`mlflow ui --backend-store-uri sqlite:///outputs/mlflow/mlflow.db` shows it). The experiment is
MLFLOW_EXPERIMENT_NAME's, else "neurosym". A run that starts over replaces (deletes, restorably) the run of its
key; a resumed one continues it. The runs of one baseline of one (task, budget, training seed) are the children of
one parent run (``TrackedRun.group``), so each baseline and seed is one run in MLflow's list, its stages nested."""

from __future__ import annotations

import importlib.util
import logging
import os
import time
from contextlib import contextmanager, nullcontext
from pathlib import Path
from typing import Iterator, Mapping

from ..errors import UserError, cut
from .tracking import TrackedRun, Tracker, missing

STORE, DATABASE, ARTIFACTS = "mlflow", "mlflow.db", "artifacts"
"""the default store's folder under the runs root, its SQLite file and its artifact folder"""
EXPERIMENT = "neurosym"
"""the experiment of every run unless MLFLOW_EXPERIMENT_NAME names another"""
KEY, GROUP = "neurosym.run", "neurosym.group"
"""the tags that hold a run's key (TrackedRun.key: how a resume finds its run) and a parent run's group"""
GROUP_TAGS = ("task", "budget", "baseline", "seed")
"""the tags a parent run carries: what its children share"""
BATCH, PARAMS_PER_CALL, FLUSH_SECONDS = 1000, 100, 10.0
"""metrics per log_batch (MLflow's limit), parameters per call (its limit), and the longest a metric waits"""


@contextmanager
def _held(folder: Path) -> Iterator[None]:
    """One process at a time creates the default store's tables and experiment (a sweep's jobs start together)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not on Linux or macOS
        yield
        return
    with open(folder / ".lock", "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)  # released on close
        yield


def _client(run: TrackedRun):
    """(MlflowClient, experiment id, the default store's folder or None) of the configured store; one line when it
    cannot be opened."""
    try:
        from mlflow.tracking import MlflowClient
    except ImportError:
        raise missing("mlflow") from None
    uri = os.environ.get("MLFLOW_TRACKING_URI", "").strip()
    name = os.environ.get("MLFLOW_EXPERIMENT_NAME", "").strip() or EXPERIMENT
    folder = None
    if not uri:
        from .io import check_inside

        if not all(importlib.util.find_spec(m) for m in ("sqlalchemy", "alembic")):  # mlflow-skinny alone: no SQLite
            raise missing("mlflow")
        folder = (run.store / STORE).resolve()
        check_inside(folder)
        folder.mkdir(parents=True, exist_ok=True)
        uri = f"sqlite:///{folder / DATABASE}"
        for quiet in ("alembic", "mlflow.store.db.utils"):  # "creating initial tables": no news for a user
            logging.getLogger(quiet).setLevel(logging.WARNING)
    try:
        with _held(folder) if folder else nullcontext():
            client = MlflowClient(tracking_uri=uri)
            exp = client.get_experiment_by_name(name)
            if exp is None:
                where = (folder / ARTIFACTS).as_uri() if folder else None
                return client, client.create_experiment(name, artifact_location=where), folder
            return client, exp.experiment_id, folder
    except ImportError:  # the SQLite store's sqlalchemy or alembic
        raise missing("mlflow") from None
    except Exception as e:  # a server that does not answer, a database that is not one: what it said, one line
        raise UserError(f"logger=mlflow cannot open the MLflow store {uri}: {cut(_first_line(e), 300)} (set "
                        "MLFLOW_TRACKING_URI to another, or unset it for the one under the runs root)") from None


def _first_line(e: Exception) -> str:
    text = str(e).strip()
    return f"{type(e).__name__}: {text.splitlines()[0] if text else ''}"


class MLflowTracker(Tracker):
    """One run of an MLflow store (``_client``), opened or resumed at construction."""

    def __init__(self, run: TrackedRun):
        self.client, exp, folder = _client(run)  # first: a missing package is one line
        from mlflow.entities import Param, RunStatus, ViewType

        with _held(folder) if folder else nullcontext():  # a sweep's jobs of one baseline: one parent
            parent = self._parent(exp, run)

        found = self.client.search_runs([exp], filter_string=f"tags.`{KEY}` = '{run.key}'",
                                        run_view_type=ViewType.ACTIVE_ONLY, order_by=["attributes.start_time DESC"])
        if run.start and found:  # a resumed training continues its run
            self.id = found[0].info.run_id
            self.client.update_run(self.id, status=RunStatus.to_string(RunStatus.RUNNING))
            have = found[0].data.params
        else:  # a run that starts over replaces the one of its key, as its CSV file does
            for old in found:
                self.client.delete_run(old.info.run_id)
            self.id = self.client.create_run(exp, run_name=run.key, tags={
                KEY: run.key, **run.tags, "mlflow.parentRunId": parent}).info.run_id
            have = {}
        params = [Param(k, str(v)[:6000]) for k, v in run.params.items() if k not in have]  # MLflow's longest
        for i in range(0, len(params), PARAMS_PER_CALL):
            self.client.log_batch(self.id, params=params[i:i + PARAMS_PER_CALL])
        self.pending: list = []
        self.flushed = time.monotonic()

    def _parent(self, exp: str, run: TrackedRun) -> str:
        """The id of the parent run of ``run.group``, made the first time (finished at once: it holds no data)."""
        from mlflow.entities import ViewType

        found = self.client.search_runs([exp], filter_string=f"tags.`{GROUP}` = '{run.group}'",
                                        run_view_type=ViewType.ACTIVE_ONLY, max_results=1,
                                        order_by=["attributes.start_time ASC"])  # two made at once: all take the first
        if found:
            return found[0].info.run_id
        made = self.client.create_run(exp, run_name=run.group, tags={
            GROUP: run.group, **{k: run.tags[k] for k in GROUP_TAGS if k in run.tags}}).info.run_id
        self.client.set_terminated(made, "FINISHED")
        return made

    def log(self, step: int, metrics: Mapping[str, float]) -> None:
        from mlflow.entities import Metric

        now = int(time.time() * 1000)
        self.pending += [Metric(k, float(v), now, step) for k, v in metrics.items()]
        if len(self.pending) >= BATCH or time.monotonic() - self.flushed > FLUSH_SECONDS:
            self.flush()

    def flush(self) -> None:
        """Send the metrics logged since the last flush, BATCH at a time (one SQLite transaction each)."""
        while self.pending:
            self.client.log_batch(self.id, metrics=self.pending[:BATCH])
            self.pending = self.pending[BATCH:]
        self.flushed = time.monotonic()

    def summary(self, metrics: Mapping[str, float]) -> None:
        self.log(0, metrics)

    def artifact(self, path: Path, folder: str = "") -> None:
        self.client.log_artifact(self.id, str(path), artifact_path=folder or None)

    def close(self, failed: bool = False) -> None:
        try:
            self.flush()
        finally:
            self.client.set_terminated(self.id, "FAILED" if failed else "FINISHED")

