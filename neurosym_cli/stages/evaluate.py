"""Evaluate one baseline into its run directory: the protocol of paper section 4 (``evaluation.evaluate``) over
``budget.eval_seeds`` seeds, written to eval/<label>/metrics.json and metrics.csv."""

from __future__ import annotations

import math
import time

from .. import __version__
from ..config import RunConfig
from ..evaluation import evaluate, summarize
from ..utils.console import log
from ..utils.cpu import runtime
from ..utils.device import resolve_device
from ..utils.io import ArtifactError, csv_bytes, json_bytes, write_together
from ..utils.lock import run_lock
from ..utils.seeding import seed_everything
from . import RunInfo
from ..run import RunDir, train_command
from ..run.layout import METRICS_CSV, METRICS_FILE
from ..run.models import load_baseline


def evaluate_baseline(cfg: RunConfig, info: RunInfo, label: str | None = None) -> dict:
    """Mean, std and 95 % interval over seeds of every metric; per-seed rows beside them. ``label`` names the row
    and its directory instead of the baseline's own label (`neurosym rl`'s picks rl1, rl2)."""
    device = resolve_device(cfg.device)
    seed_everything(cfg.seed)
    policy, env, comm = load_baseline(cfg, device)
    seeds = list(range(cfg.budget.eval_seeds))
    t0 = time.perf_counter()
    rows = evaluate(env, policy, comm, seeds, device, cfg.task.detach_state)
    seconds = time.perf_counter() - t0
    bad = next((f"{k} of seed {r['seed']}" for r in rows for k, v in r.items()
                if isinstance(v, float) and not math.isfinite(v)), None)
    if bad:  # finite weights whose rollouts overflow: a nan is never a result, nor written over one
        raise ArtifactError(f"evaluating {label or RunDir(cfg).label} gave a non-finite {bad}; nothing "
                            f"written: the model's rollouts diverge, `{train_command(cfg)} overwrite=true` "
                            "trains it again (a smaller optim.lr, or smaller task scales: task.dt, task.v_max)")
    summary = summarize(rows)
    out = RunDir(cfg).eval_dir(label)
    label = label or RunDir(cfg).label
    with run_lock(out):
        _write(cfg, info, out, label=label, rows=rows, summary=summary, seconds=seconds,
               rules=cfg.baseline.rules(cfg, comm))
    log.info("evaluated %s on %d seeds in %.1f s -> %s", label, len(seeds), seconds, out)
    return summary


def _write(cfg: RunConfig, info: RunInfo, out, *, label: str, rows: list[dict], summary: dict, seconds: float,
           rules: int) -> None:
    write_together({out / METRICS_CSV: csv_bytes(rows), out / METRICS_FILE: json_bytes({
        "baseline": cfg.baseline.name, "label": label, "task": cfg.task.name, "rules": rules,
        "seeds": len(rows), "episodes_per_seed": rows[0]["episodes"], "summary": summary, "per_seed": rows,
        "model": str(RunDir(cfg).model_file), "seconds": seconds, "version": __version__,
        "runtime": runtime(), "config": cfg.record(),
    })})  # both or neither: a full disk never pairs a new table with an old record
