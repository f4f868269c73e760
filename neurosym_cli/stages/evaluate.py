"""Evaluate one baseline into its run directory: the protocol of paper section 4 (``evaluation.evaluate``) over
``budget.eval_seeds`` seeds, written to eval/<label>/metrics.json and metrics.csv."""

from __future__ import annotations

import time

from .. import __version__, artifacts, paths
from ..config import RunConfig
from ..envs import make_env
from ..evaluation import evaluate, summarize
from ..utils.console import log
from ..utils.device import resolve_device
from ..utils.lock import run_lock
from ..utils.seeding import seed_everything
from . import RunInfo
from .comm import baseline_comm


def evaluate_baseline(cfg: RunConfig, info: RunInfo) -> dict:
    """Mean, std and 95 % interval over seeds of every metric; per-seed rows beside them."""
    device = resolve_device(cfg.device)
    seed_everything(cfg.seed)
    payload = artifacts.load_checkpoint(paths.train_dir(cfg) / "model.pt", paths.train_command(cfg))
    if not payload.get("done"):
        log.warning("the model is only partly trained (step %d); evaluating it anyway; `%s` finishes it",
                    payload["fit"]["step"], paths.train_command(cfg))
    policy = artifacts.policy_from_payload(payload).to(device)
    env = make_env(cfg.task, cfg.horizon)
    comm = baseline_comm(cfg)
    seeds = list(range(cfg.budget.eval_seeds))
    t0 = time.perf_counter()
    rows = evaluate(env, policy, comm, seeds, device, cfg.task.detach_state)
    seconds = time.perf_counter() - t0
    summary = summarize(rows)
    label = paths.baseline_label(cfg)
    out = paths.eval_dir(cfg)
    with run_lock(out):
        _write(cfg, info, out, label, rows, summary, seconds)
    log.info("evaluated %s on %d seeds in %.1f s -> %s", label, len(seeds), seconds, out)
    return summary


def _write(cfg: RunConfig, info: RunInfo, out, label: str, rows: list[dict], summary: dict, seconds: float) -> None:
    artifacts.write_csv(out / "metrics.csv", rows)
    artifacts.write_json(out / "metrics.json", {
        "baseline": cfg.baseline.name, "label": label, "task": cfg.task.name, "rules": cfg.rules,
        "seeds": len(rows), "episodes_per_seed": rows[0]["episodes"], "summary": summary, "per_seed": rows,
        "model": str(paths.train_dir(cfg) / "model.pt"), "seconds": seconds, "version": __version__,
        "config": info.config,
    })
