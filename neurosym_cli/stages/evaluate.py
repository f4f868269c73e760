"""Evaluate one baseline into its run directory: the protocol of paper section 4 (``evaluation.evaluate``) over
``budget.eval_seeds`` seeds, written to eval/<label>/metrics.json and metrics.csv."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Callable, Sequence

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
from .tracked import open_run


def evaluate_baseline(cfg: RunConfig, info: RunInfo, label: str | None = None, *,
                      then: Callable[[], Sequence[Path]] | None = None) -> dict:
    """Mean, std and 95 % interval over seeds of every metric; per-seed rows beside them. ``label`` names the row
    and its directory instead of the baseline's own label (`neurosym rl`'s picks rl1, rl2); ``then``: what the
    command does once the evaluation is written (its table and figures), returning the figures it drew, which the
    run tracker (logger=) keeps with the evaluation."""
    device = resolve_device(cfg.device)
    seed_everything(cfg.seed)
    policy, env, comm = load_baseline(cfg, device)
    seeds = list(range(cfg.budget.eval_seeds))
    name = label or RunDir(cfg).label
    with open_run(cfg, stage="eval", run=f"eval-{name}", label=name) as tracker:
        t0 = time.perf_counter()
        rows = evaluate(env, policy, comm, seeds, device, cfg.task.detach_state)
        seconds = time.perf_counter() - t0
        bad = next((f"{k} of seed {r['seed']}" for r in rows for k, v in r.items()
                    if isinstance(v, float) and not math.isfinite(v)), None)
        if bad:  # finite weights whose rollouts overflow: a nan is never a result, nor written over one
            raise ArtifactError(f"evaluating {name} gave a non-finite {bad}; nothing written: the model's rollouts "
                                f"diverge, `{train_command(cfg)} overwrite=true` trains it again (a smaller "
                                "optim.lr, or smaller task scales: task.dt, task.v_max)")
        summary = summarize(rows)
        out = RunDir(cfg).eval_dir(label)
        with run_lock(out):
            _write(cfg, info, out, label=name, rows=rows, summary=summary, seconds=seconds,
                   rules=cfg.baseline.rules(cfg, comm))
        log.info("evaluated %s on %d seeds in %.1f s -> %s", name, len(seeds), seconds, out)
        tracker.summary({f"eval/{m}/{k}": v for m, stats in summary.items() for k, v in stats.items()})
        for f in (out / METRICS_FILE, out / METRICS_CSV, *(then() if then else ())):
            tracker.artifact(f)
    return summary


def _write(cfg: RunConfig, info: RunInfo, out, *, label: str, rows: list[dict], summary: dict, seconds: float,
           rules: int) -> None:
    write_together({out / METRICS_CSV: csv_bytes(rows), out / METRICS_FILE: json_bytes({
        "baseline": cfg.baseline.name, "label": label, "task": cfg.task.name, "rules": rules,
        "seeds": len(rows), "episodes_per_seed": rows[0]["episodes"], "summary": summary, "per_seed": rows,
        "model": str(RunDir(cfg).model_file), "seconds": seconds, "version": __version__,
        "runtime": runtime(), "config": cfg.record(),
    })})  # both or neither: a full disk never pairs a new table with an old record
