"""The only module that knows file names and formats of run artifacts.

Layout of one experiment directory (``exp_dir`` = outputs/<task>/<budget>/seed<k>):
    train/<model>/model.pt          checkpoint: weights, the model's own config, resume state
    train/<model>/history.csv       one row per optimizer step
    train/<model>/manifest.json     what made it (command, config, versions)
    eval/<baseline>/metrics.json    summary (mean, std over seeds) plus per-seed rows and the config
    eval/<baseline>/metrics.csv     per-seed rows
Every write goes to a temporary file in the same directory and is renamed into place, so an interrupted run
never leaves a half-written artifact. Checkpoints are loaded with ``weights_only=True`` (never unpickled).
"""

from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from dataclasses import asdict
from pathlib import Path
from typing import Any, Mapping, Sequence

import torch

from .config import ModelConfig, RunConfig, UserError
from .policy.transformer import CommTransformer

CHECKPOINT_FORMAT = "neurosym-policy/1"


class ArtifactError(UserError):
    """A required artifact is missing or unreadable; the message says which command makes it."""


# ------------------------------------------------------------------------------------------------ paths
def model_name(cfg: RunConfig) -> str:
    """Directory name of the weights a baseline uses: the shared oracle, or its own trained model."""
    if cfg.baseline.model == "oracle":
        return "oracle"
    return cfg.baseline.name if cfg.baseline.comm == "none" else f"{cfg.baseline.name}-k{cfg.rules}"


def baseline_label(cfg: RunConfig) -> str:
    """Name of a baseline's evaluation directory (k is part of it where the mask depends on k)."""
    return cfg.baseline.name if cfg.baseline.comm in ("full", "none") else f"{cfg.baseline.name}-k{cfg.rules}"


def train_dir(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "train" / model_name(cfg)


def eval_dir(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "eval" / baseline_label(cfg)


# ------------------------------------------------------------------------------------------ atomic I/O
def atomic_write_bytes(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_text(path: Path, text: str) -> None:
    atomic_write_bytes(path, text.encode())


def write_json(path: Path, obj: Any) -> None:
    write_text(path, json.dumps(obj, indent=2, sort_keys=False) + "\n")


def write_csv(path: Path, rows: Sequence[Mapping[str, Any]]) -> None:
    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    write_text(path, buf.getvalue())


def read_json(path: Path) -> Any:
    try:
        return json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as e:
        raise ArtifactError(f"cannot read {path}: {e}") from None


def save_checkpoint(path: Path, payload: dict[str, Any]) -> None:
    buf = io.BytesIO()
    torch.save(payload, buf)
    atomic_write_bytes(Path(path), buf.getvalue())


def load_checkpoint(path: Path, made_by: str) -> dict[str, Any]:
    """Load a checkpoint safely; ``made_by`` is the command that creates it (named in the error)."""
    path = Path(path)
    if not path.exists():
        raise ArtifactError(f"no checkpoint at {path}; create it with `{made_by}`")
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # truncated file, foreign pickle, wrong format: all the same to the user
        raise ArtifactError(f"corrupt checkpoint {path} ({type(e).__name__}); delete it and re-run `{made_by}`") from None
    if not isinstance(payload, dict) or payload.get("format") != CHECKPOINT_FORMAT:
        raise ArtifactError(f"{path} is not a neurosym policy checkpoint; re-run `{made_by}`")
    return payload


# ------------------------------------------------------------------------------------------- policies
def policy_payload(policy: CommTransformer, model_cfg: ModelConfig, run_cfg: dict, fit: dict, done: bool) -> dict:
    """A self-describing checkpoint: the weights plus everything needed to rebuild and resume the model."""
    return {
        "format": CHECKPOINT_FORMAT,
        "state_dict": policy.state_dict(),
        "arch": {"obs_dim": policy.obs_dim, "action_dim": policy.action_dim, "rounds": policy.n_rounds,
                 **asdict(model_cfg)},
        "config": run_cfg,
        "fit": fit,
        "done": done,
    }


def policy_from_payload(payload: dict[str, Any]) -> CommTransformer:
    arch = dict(payload["arch"])
    model = CommTransformer(arch.pop("obs_dim"), arch.pop("action_dim"), arch.pop("rounds"), ModelConfig(**arch))
    model.load_state_dict(payload["state_dict"])
    return model
