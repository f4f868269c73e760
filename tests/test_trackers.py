"""logger=mlflow and logger=wandb against real stores: a tiny pipeline tracked into a temporary runs root, then the
MLflow store opened with MLflow's client and W&B's offline run files read with W&B's own record schema."""

import csv
import importlib.util
import json
import os
import struct
import subprocess
import sys
from pathlib import Path

import pytest

from test_cli import run

TRACKERS = [t for t in ("mlflow", "wandb") if importlib.util.find_spec(t)]
COMBINED = "+".join(["tensorboard"] * bool(importlib.util.find_spec("tensorboard")) + TRACKERS)
"""the pipeline's logger=: every tracker installed here at once"""
EXP = "random-grid/tiny/seed0"


@pytest.fixture(autouse=True)
def _own_stores(monkeypatch):
    """The stores under the test's runs root, whatever the developer's shell points at: no server, no account."""
    for name in ("MLFLOW_TRACKING_URI", "MLFLOW_EXPERIMENT_NAME", "WANDB_API_KEY", "WANDB_PROJECT", "WANDB_ENTITY",
                 "WANDB_BASE_URL", "WANDB_DIR"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("WANDB_MODE", "offline")


def _csv(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# --- MLflow -----------------------------------------------------------------------------------------------------

def _mlflow_runs(root: Path) -> dict:
    from mlflow.entities import ViewType
    from mlflow.tracking import MlflowClient

    client = MlflowClient(tracking_uri=f"sqlite:///{root / 'mlflow/mlflow.db'}")
    exp = client.get_experiment_by_name("neurosym")
    runs = client.search_runs([exp.experiment_id], run_view_type=ViewType.ALL)
    return client, {(r.info.lifecycle_stage, r.data.tags["neurosym.run"]): r for r in runs
                    if "neurosym.run" in r.data.tags}  # the stages' runs; their parents hold neurosym.group


def _mlflow_parents(root: Path) -> dict:
    """group -> the parent run of one baseline of one (task, budget, seed)."""
    from mlflow.tracking import MlflowClient

    client = MlflowClient(tracking_uri=f"sqlite:///{root / 'mlflow/mlflow.db'}")
    exp = client.get_experiment_by_name("neurosym")
    return {r.data.tags["neurosym.group"]: r for r in client.search_runs([exp.experiment_id])
            if "neurosym.group" in r.data.tags}


def _tag(tracked: Path) -> str:
    """The program's tag (k2-lam0.5-v1 and the search's non-default settings), read from the run directory."""
    return next((tracked / EXP / "synth").glob("*/program.txt")).parent.name


def _check_mlflow(tracked: Path) -> None:
    """Every stage of the pipeline is one finished MLflow run with its tags, config, steps, summary and files."""
    tag = _tag(tracked)
    client, runs = _mlflow_runs(tracked)
    assert sorted(k for _, k in runs) == [f"{EXP}/eval-prog-{tag}", f"{EXP}/figures", f"{EXP}/synth-{tag}",
                                          f"{EXP}/train-oracle"]
    # one parent run per baseline of this (task, budget, seed), its stages nested under it
    parents = _mlflow_parents(tracked)
    assert sorted(parents) == [f"{EXP}/figures", f"{EXP}/prog-{tag}", f"{EXP}/tf-full"]
    assert parents[f"{EXP}/tf-full"].data.tags["seed"] == "0" and parents[f"{EXP}/tf-full"].info.status == "FINISHED"
    nest = {k: r.data.tags["mlflow.parentRunId"] for (_, k), r in runs.items()}
    assert nest[f"{EXP}/train-oracle"] == parents[f"{EXP}/tf-full"].info.run_id
    assert nest[f"{EXP}/synth-{tag}"] == nest[f"{EXP}/eval-prog-{tag}"] == parents[f"{EXP}/prog-{tag}"].info.run_id
    # the pipeline's pictures: the table's plot, the training curves and the figures of the run
    pictures = {a.path for a in client.list_artifacts(runs["active", f"{EXP}/figures"].info.run_id)}
    assert {"figure2.png", "curves.png"} <= pictures and len(pictures) == len(list(
        (tracked / EXP / "figures").glob("*.png"))) + 2
    train = runs["active", f"{EXP}/train-oracle"]
    assert train.info.status == "FINISHED"
    assert {k: train.data.tags[k] for k in ("task", "budget", "baseline", "scheme", "seed", "stage")} == {
        "task": "random-grid", "budget": "tiny", "baseline": "tf-full", "scheme": "tf-full", "seed": "0",
        "stage": "train"}
    p = train.data.params
    assert p["budget.name"] == "tiny" and p["threads"] == "1" and "mlflow" in p["logger"].split("+")
    assert float(p["optim.lr"]) > 0 and len(p) > 50  # the whole config, flattened
    hist = _csv(tracked / EXP / "train/oracle/history.csv")
    loss = client.get_metric_history(train.info.run_id, "train/loss")
    loss = sorted(loss, key=lambda m: m.step)
    assert [m.step for m in loss] == [int(h["step"]) for h in hist]
    assert [m.value for m in loss] == pytest.approx([float(h["loss"]) for h in hist])
    assert {a.path for a in client.list_artifacts(train.info.run_id)} == {"history.csv", "manifest.json"}

    synth = runs["active", f"{EXP}/synth-{tag}"]
    assert synth.data.tags["stage"] == "synth" and synth.data.tags["scheme"] == "prog"
    best = sorted(client.get_metric_history(synth.info.run_id, "search/best"), key=lambda m: m.step)
    trace = _csv(tracked / EXP / f"synth/{tag}/trace.csv")
    assert [m.value for m in best] == pytest.approx([float(r["best"]) for r in trace])  # every proposal
    arts = {a.path for a in client.list_artifacts(synth.info.run_id)}
    assert {"program.txt", "summary.json", "trace.csv"} <= arts
    program = Path(client.download_artifacts(synth.info.run_id, "program.txt", str(tracked / "dl")))
    assert program.read_text() == (tracked / EXP / f"synth/{tag}/program.txt").read_text()

    ev = runs["active", f"{EXP}/eval-prog-{tag}"]
    metrics = json.loads((tracked / EXP / f"eval/prog-{tag}/metrics.json").read_text())["summary"]
    assert ev.data.metrics["eval/cost/mean"] == pytest.approx(metrics["cost"]["mean"])
    assert ev.data.metrics["eval/cost/ci95"] == pytest.approx(metrics["cost"]["ci95"])
    assert {"metrics.json", "metrics.csv"} <= {a.path for a in client.list_artifacts(ev.info.run_id)}


def _check_mlflow_eval_again(tracked: Path) -> None:
    """`neurosym eval` again replaces the pipeline's evaluation run (deleted, restorable) and keeps its figures."""
    tag = _tag(tracked)
    run(["eval", "budget=tiny", "task=random-grid", "threads=1", "baseline=prog", "logger=mlflow"], tracked,
        plots=True)
    client, runs = _mlflow_runs(tracked)
    key = f"{EXP}/eval-prog-{tag}"
    assert ("deleted", key) in runs and sum(k == key for s, k in runs if s == "active") == 1
    again = runs["active", key]
    assert {"metrics.json", "figure2.png", "curves.png"} <= {a.path for a in client.list_artifacts(again.info.run_id)}


# --- W&B (offline) -----------------------------------------------------------------------------------------------

def _records(path: Path) -> list:
    """Every record of a W&B transaction log (run-<id>.wandb): a 7-byte header, then LevelDB log blocks of 32 KiB
    whose records carry W&B's protobuf Record."""
    from wandb.proto import wandb_internal_pb2 as pb

    data, out, part, pos = path.read_bytes(), [], b"", 7
    assert data[:4] == b":W&B"
    while pos + 7 <= len(data):
        room = 32768 - pos % 32768
        _crc, length, kind = struct.unpack("<IHB", data[pos:pos + 7])
        if room < 7 or kind == 0:  # a block's zero padding
            pos += room
            continue
        part, pos = part + data[pos + 7:pos + 7 + length], pos + 7 + length
        if kind in (1, 4):  # FULL or LAST
            rec = pb.Record()
            rec.ParseFromString(part)
            out.append(rec)
            part = b""
    return out


def _run_record(path: Path):
    """The run record (id, name, group, job type, tags, config) of one W&B transaction log."""
    return next(r.run for r in _records(path) if r.WhichOneof("record_type") == "run")


def _wandb_runs(root: Path) -> dict:
    """job type -> (run record, [history rows], summary, files saved) of every offline run under ``root``."""
    runs = {}
    for f in sorted((root / "wandb").glob("offline-run-*/run-*.wandb")):
        recs = _records(f)
        head = _run_record(f)
        rows = [{i.nested_key[0] if i.nested_key else i.key: json.loads(i.value_json) for i in r.history.item}
                for r in recs if r.WhichOneof("record_type") == "history"]
        summary = {u.key or "/".join(u.nested_key): json.loads(u.value_json)
                   for r in recs if r.WhichOneof("record_type") == "summary" for u in r.summary.update}
        files = [fi.path for r in recs if r.WhichOneof("record_type") == "files" for fi in r.files.files]
        runs[head.display_name] = (head, rows, summary, files, f.parent)
    return runs


def _check_wandb(tracked: Path) -> None:
    """Every stage of the pipeline is one offline W&B run with its group, config, steps, summary and files."""
    tag = _tag(tracked)
    runs = _wandb_runs(tracked)
    assert sorted(runs) == [f"{EXP}/eval-prog-{tag}", f"{EXP}/figures", f"{EXP}/synth-{tag}", f"{EXP}/train-oracle"]
    assert {"figure2.png", "curves.png"} <= set(runs[f"{EXP}/figures"][3])  # the pipeline's pictures
    head, rows, summary, files, folder = runs[f"{EXP}/train-oracle"]
    assert head.job_type == "train" and head.run_group == f"{EXP}/tf-full" and head.project == "neurosym"
    assert {"random-grid", "tiny", "tf-full", "0", "train"} <= set(head.tags)
    config = {u.key: json.loads(u.value_json) for u in head.config.update}
    assert config["budget.name"] == "tiny" and config["threads"] == 1 and config["neurosym.stage"] == "train"
    hist = _csv(tracked / EXP / "train/oracle/history.csv")
    assert [r["train/step"] for r in rows if "train/loss" in r] == [int(h["step"]) for h in hist]
    assert [r["train/loss"] for r in rows if "train/loss" in r] == pytest.approx([float(h["loss"]) for h in hist])
    assert summary["train/final_loss"] == pytest.approx(json.loads(
        (tracked / EXP / "train/oracle/manifest.json").read_text())["final_loss"])
    assert {"history.csv", "manifest.json"} <= set(files)

    head, rows, summary, files, folder = runs[f"{EXP}/synth-{tag}"]
    trace = _csv(tracked / EXP / f"synth/{tag}/trace.csv")
    assert head.job_type == "synth"
    assert [r["search/best"] for r in rows if "search/best" in r] == pytest.approx([float(r["best"]) for r in trace])
    assert "program.txt" in files
    assert (folder / "files/program.txt").read_text() == (tracked / EXP / f"synth/{tag}/program.txt").read_text()

    head, rows, summary, files, folder = runs[f"{EXP}/eval-prog-{tag}"]
    assert head.run_group == f"{EXP}/prog-{tag}" and head.job_type == "eval"
    metrics = json.loads((tracked / EXP / f"eval/prog-{tag}/metrics.json").read_text())["summary"]
    assert summary["eval/cost/mean"] == pytest.approx(metrics["cost"]["mean"])
    assert {"metrics.json", "metrics.csv"} <= set(files)
    assert not list(Path(tracked).glob("*.wandb"))  # every file under <runs_root>/wandb


def test_a_tracked_pipeline_lands_in_every_installed_store(tmp_path):
    """One tiny pipeline (train, synth, eval of prog) tracked by every tracker installed here at once."""
    if not TRACKERS:
        pytest.skip("neither mlflow nor wandb is installed (pip install -e '.[mlflow,wandb]')")
    run(["pipeline", "budget=tiny", "task=random-grid", "threads=1", "baselines=[prog]", "pipeline.select=none",
         f"logger={COMBINED}"], tmp_path, timeout=600, plots=True)
    if "mlflow" in TRACKERS:
        _check_mlflow(tmp_path)
    if "wandb" in TRACKERS:
        _check_wandb(tmp_path)
    if "mlflow" in TRACKERS:
        _check_mlflow_eval_again(tmp_path)
    _check_resume(tmp_path)


def _check_resume(tracked: Path) -> None:
    """A training extended from its checkpoint (steps 3, 4 after 1, 2) continues its tracked run."""
    run(["train", "budget=tiny", "task=random-grid", "threads=1", "budget.train_rollouts=16",
         f"logger={'+'.join(TRACKERS)}"], tracked)
    key = f"{EXP}/train-oracle"
    if "mlflow" in TRACKERS:
        client, runs = _mlflow_runs(tracked)
        assert [s for s, k in runs if k == key] == ["active"]
        loss = client.get_metric_history(runs["active", key].info.run_id, "train/loss")
        assert sorted(m.step for m in loss) == [1, 2, 3, 4]
    if "wandb" in TRACKERS:
        ids = {_run_record(f).run_id for f in (tracked / "wandb").glob("offline-run-*/run-*.wandb")
               if _run_record(f).display_name == key}
        assert len(ids) == 1 and len(list((tracked / "wandb").glob(f"offline-run-*-{ids.pop()}"))) == 2


# --- missing packages ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("tracker", ["mlflow", "wandb"])
def test_missing_tracker_package_is_one_line_naming_the_extra(tracker, tmp_path):
    code = (f"import sys; sys.modules[{tracker!r}] = None; from neurosym_cli.cli import main; "
            f"sys.argv = ['neurosym', 'train', 'budget=tiny', 'task=random-grid', 'threads=1', "
            f"'logger=csv+{tracker}']; main()")
    p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                       env={**os.environ, "NEUROSYM_RUNS": str(tmp_path)})
    assert p.returncode == 1 and "Traceback" not in p.stderr
    assert p.stderr.strip().splitlines()[-1] == (
        f"neurosym train: error: logger={tracker} needs the {tracker} extra: pip install -e '.[{tracker}]' in the "
        f"neurosym checkout (or pip install {'mlflow-skinny sqlalchemy alembic' if tracker == 'mlflow' else tracker};"
        " or logger=csv)")
    assert not (tmp_path / EXP / "train/oracle/model.pt").exists()  # refused before any training


def test_mlflow_without_its_sqlite_store_names_the_extra(monkeypatch, tmp_path):
    pytest.importorskip("mlflow", reason="logger=mlflow needs the mlflow extra")
    from neurosym_cli.errors import UserError
    from neurosym_cli.utils.tracking import TrackedRun, open_tracker

    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    monkeypatch.setitem(sys.modules, "sqlalchemy", None)  # mlflow-skinny alone reads no SQLite store
    with pytest.raises(UserError, match=r"^logger=mlflow needs the mlflow extra: pip install -e '\.\[mlflow\]'"):
        open_tracker("mlflow", TrackedRun(key="t/b/seed0/train-oracle", tags={}, store=tmp_path))
    assert not (tmp_path / "mlflow/mlflow.db").exists()


def test_logger_choices_are_checked_in_one_line(tmp_path):
    from neurosym_cli.utils.tracking import logger_problem, trackers

    assert trackers("csv") == () and trackers("tensorboard+mlflow+csv+mlflow") == ("tensorboard", "mlflow")
    assert logger_problem("wandb+tensorboard") is None
    p = run(["train", "budget=tiny", "logger=mlflow+neptune"], tmp_path, check=False)
    assert p.returncode == 2 and p.stderr.strip() == (
        "neurosym train: error: logger='mlflow+neptune': choose csv, tensorboard, mlflow or wandb, several joined "
        "by + (logger=tensorboard+mlflow); csv is always written")
    p = run(["train", "budget=tiny", "logger=[tensorboard,mlflow]"], tmp_path, check=False)
    assert p.returncode == 2 and "join trackers by + (logger=tensorboard+mlflow)" in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1
