"""Validation (the paper's appendix B): a baseline's loss and degree per validation seed (``validate``), and the
rule that chooses among such rows (``choose``: the lowest degree among those statistically similar to the best).
Used by `neurosym select` (over a lam grid), `neurosym rl` (its picks) and pipeline.select=front (over a front)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Sequence

from ..config import RunConfig, UserError
from ..run import RunDir
from ..stats import mean_ci  # the project's one Student-t interval
from ..utils.io import read_json, write_json

DEGREE = "max_degree"
"""the degree the rule prefers lower: the paper's deg, max over agents of in- plus out-degree (eval's max deg)"""


def choose(rows: Sequence[dict[str, Any]], *, margin: float | None = None,
           reference: Sequence[float] | None = None) -> list[dict[str, Any]]:
    """The paper's rule on validation rows. Each row has ``name``, ``loss`` (per validation seed, the same seeds in
    the same order for every row) and ``degree`` (its mean over those seeds).

    Returns the rows annotated, ordered by (not similar, degree, loss): ``loss_mean``, ``loss_ci``, ``diff`` (mean
    paired difference to the best), ``diff_ci`` (its 95 % half-width), ``similar``, ``best`` (the rows' own
    validation-best) and ``picked`` (the lowest degree among the similar rows, the lower mean loss on a tie).
    ``similar``: without ``margin``, the interval contains 0 (the difference is not significant: the paper's appendix
    B); with it, an equivalence test, the interval's upper end is at most ``margin`` x |the best's mean loss| (a noisy
    row is no longer similar just because its interval is wide). The best is the rows' own validation-best, or
    ``reference`` (losses per validation seed of a row from elsewhere: another family's best) where its mean is
    lower; then no row may be similar (two families' models rarely tie within the paper's test), and the rows are
    ordered by mean loss, the lowest picked."""
    if not rows:
        raise ValueError("nothing to choose from")
    seeds = {len(r["loss"]) for r in rows} | ({len(reference)} if reference is not None else set())
    if len(seeds) != 1:
        raise ValueError(f"rows are evaluated on different numbers of seeds: {sorted(seeds)}")
    out = [dict(r) for r in rows]
    for r in out:
        r["loss_mean"], r["loss_ci"] = mean_ci(r["loss"])
    own = min(out, key=lambda r: r["loss_mean"])
    best = own["loss"]
    if reference is not None and mean_ci(list(reference))[0] < own["loss_mean"]:
        best = list(reference)
    best_mean = mean_ci(best)[0]
    for r in out:
        d = [a - b for a, b in zip(r["loss"], best)]
        r["diff"], r["diff_ci"] = mean_ci(d)
        r["similar"] = r["loss"] == best or (r["diff"] <= r["diff_ci"] if margin is None
                                              else r["diff"] + r["diff_ci"] <= margin * abs(best_mean))
        r["best"] = r is own
        r["picked"] = False
    out.sort(key=lambda r: (not r["similar"], r["degree"], r["loss_mean"]))
    if not out[0]["similar"]:  # nothing as good as the reference: the closest
        out.sort(key=lambda r: r["loss_mean"])
    out[0]["picked"] = True
    return out


def _val_file(cfg: RunConfig) -> Path:
    return RunDir(cfg).val_file(RunDir(cfg).label)


def validate(cfg: RunConfig) -> dict[str, Any]:
    """Validation rows of ``cfg``'s baseline (prog, prog-retrained, rl): per validation seed the loss and the degree.
    Reused when the file exists for the same program text, model and seeds."""
    import torch

    from ..evaluation import evaluate
    from ..utils.device import resolve_device
    from ..utils.seeding import seed_everything
    from ..run.models import load_baseline

    program = RunDir(cfg).program_file.read_text() if cfg.baseline.has_program else None
    model = RunDir(cfg).model_file
    stamp = {"program": program, "model": str(model), "model_mtime": model.stat().st_mtime,
             "val_seeds": cfg.budget.val_seeds}
    out = _val_file(cfg)
    if out.exists():
        try:
            old = read_json(out)
            if {k: old.get(k) for k in stamp} == stamp:
                return old
        except UserError:
            pass  # unreadable: evaluate again
    device = resolve_device(cfg.device)
    seed_everything(cfg.seed)
    policy, env, comm = load_baseline(cfg, device)
    t0 = time.perf_counter()
    with torch.no_grad():
        rows = evaluate(env, policy, comm, list(range(cfg.budget.val_seeds)), device, cfg.task.detach_state,
                        split="val")
    result = {**stamp, "label": RunDir(cfg).label, "seconds": time.perf_counter() - t0,
              "loss": [r["cost"] for r in rows], "degree_per_seed": [r[DEGREE] for r in rows],
              "max_in": sum(r["max_in"] for r in rows) / len(rows),
              "max_out": sum(r["max_out"] for r in rows) / len(rows),
              "degree": sum(r[DEGREE] for r in rows) / len(rows)}
    write_json(out, result)
    return result
