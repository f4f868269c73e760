"""`neurosym select`: the paper's model selection by validation (appendix B) over a grid of (lam, K, features).

    1. search a program for every grid point (one shared oracle dataset D; reused when it exists);
    2. evaluate each program (prog: the oracle under it) on the validation seeds (``budget.val_seeds``, episodes
       from their own stream, never a test episode);
    3. finalists: of the programs statistically similar to the validation-best (``choose``; itself included), the
       ``select.finalists`` of lowest degree (the best only when fewer similar ones have a lower degree); retrain
       each and evaluate it on the validation seeds again;
    4. the choice among the retrained finalists by the same rule, written to select/selected.json;
    5. only then the chosen program's test evaluation (prog and prog-retrained, the usual eval directories).

The paper's rule: "the ones that produced the lowest cumulative reward [cost] on a validation set of rollouts;
if the cumulative rewards are similar, we chose the ones that reduced the communication degree". Similar means
here: the paired 95 % interval (Student t, over validation seeds) of the loss difference to the best contains 0.
"""

from __future__ import annotations

import dataclasses
import os
import time
from pathlib import Path
from typing import Any

from .. import __version__
from ..schemes import get
from ..config import ConfigError, RunConfig, UserError
from ..degrees import LAM_GRIDS, LEGEND  # noqa: F401  (LAM_GRIDS re-exported)
from ..baselines import run_args
from ..run import RunDir
from ..schemes.searched import recorded_search
from .reuse import SEARCH_KEYS, searched_otherwise
from ..utils.console import clock, log, say
from ..utils.cpu import runtime
from ..utils.io import read_json, write_csv, write_json
from . import RunInfo
from .jobs import quiet_job, run_jobs
from .validation import choose, validate  # noqa: F401  (choose: the rule, read here by tests and benchmarks)

# ------------------------------------------------------------------------------------------------- the grid
def lam_grid(cfg: RunConfig) -> list[float]:
    """The lam values of the grid: select.lam, else the grid of the search's objective (``LAM_GRIDS``)."""
    return list(cfg.select.lam) or LAM_GRIDS[cfg.synth.objective]


def grid(cfg: RunConfig) -> list[RunConfig]:
    """One prog config per grid point (lam_grid x select.rules x select.features), in that order."""
    out, n = [], cfg.task.max_agents
    for k in cfg.select.rules:
        if k >= n:
            raise ConfigError(f"select.rules has K={k}, but an agent of {cfg.task.name} has at most {n - 1} others")
        for lam in lam_grid(cfg):
            for f in cfg.select.features:
                out.append(dataclasses.replace(cfg, rules=k, lam=lam, features=f, baseline=get("prog"), cmd="synth"))
    return out


def point_name(cfg: RunConfig) -> str:
    """A grid point's program tag (k5-lam0.5-v1 plus the search variant)."""
    return RunDir(cfg).program_tag


def search_job(cfg: RunConfig, info: RunInfo) -> dict[str, Any]:
    """One grid point: its program (searched or reused), then its validation rows."""
    from .synth import read_summary, synthesize

    cfg, info = quiet_job(cfg, info)
    terms = synthesize(cfg, info)
    summary = read_summary(cfg)
    return {"name": point_name(cfg), "rules": cfg.rules, "lam": cfg.lam, "features": cfg.features,
            "objective": terms.get("objective"), "l1": terms.get("l1"), "degree_term": terms.get("degree"),
            "search_seconds": sum(float(r["seconds"]) for r in summary["rounds"]),
            **_val_columns(validate(dataclasses.replace(cfg, cmd="eval")))}


def retrain_job(cfg: RunConfig, info: RunInfo) -> dict[str, Any]:
    """One finalist: the oracle retrained under its program, then its validation rows."""
    from .train import retrain

    cfg = dataclasses.replace(cfg, baseline=get("prog-retrained"), cmd="retrain")
    cfg, info = quiet_job(cfg, info)
    retrain(cfg, info)
    return {"name": point_name(cfg), **_val_columns(validate(dataclasses.replace(cfg, cmd="eval")))}


def _val_columns(v: dict[str, Any]) -> dict[str, Any]:
    return {"loss": v["loss"], "degree": v["degree"], "max_in": v["max_in"], "max_out": v["max_out"]}


# --------------------------------------------------------------------------------------------- the command
def selected_file(cfg: RunConfig) -> Path:
    return RunDir(cfg).selected_file


def select_command(cfg: RunConfig) -> str:
    return f"neurosym select {run_args(cfg)}"


def apply_selected(cfg: RunConfig) -> RunConfig:
    """``cfg`` with the recorded choice's rules, lam, features and search settings (selected=true)."""
    path = selected_file(cfg)
    if not path.exists():
        raise UserError(f"selected=true, but no selection at {path}; make it with `{select_command(cfg)}`")
    rec = read_json(path, select_command(cfg), {"rules": int, "lam": (int, float), "features": str, "synth": dict})
    try:
        synth = dataclasses.replace(cfg.synth, **recorded_search(rec["synth"]))  # absent: the search then
        return dataclasses.replace(cfg, rules=int(rec["rules"]), lam=float(rec["lam"]), features=str(rec["features"]),
                                   synth=synth, selected=False)
    except (KeyError, TypeError, ValueError) as e:
        raise UserError(f"corrupt selection {path} ({e}); `{select_command(cfg)}` makes it again") from None


def _jobs(cfg: RunConfig) -> int:
    return cfg.select.jobs or (os.cpu_count() or 1)


def run_selection(cfg: RunConfig, info: RunInfo) -> dict[str, Any]:
    """The whole selection (module docstring); returns the choice and its test metrics."""
    from ..run.checkpoints import open_checkpoint
    from .evaluate import evaluate_baseline

    points = grid(cfg)  # a bad grid is reported before a missing artifact
    open_checkpoint(cfg, oracle=True)  # fail early
    jobs = _jobs(cfg)
    t0 = time.perf_counter()
    say(f"select {cfg.task.name}: {len(points)} configurations (lam {lam_grid(cfg)}, K {cfg.select.rules}, "
        f"features {cfg.select.features}), {cfg.budget.val_seeds} validation seeds, {jobs} job(s)")
    other = searched_otherwise(cfg, points)
    if other:
        log.warning(other)
    if jobs > 1 and not RunDir(points[0]).dataset_file.exists():
        from .synth import collect_dataset

        collect_dataset(points[0])  # one D for the whole grid, collected here once (parallel jobs would each do it)
    searched = run_jobs(search_job, points, info, jobs, "program", name=point_name)
    t_search = time.perf_counter() - t0
    first = choose(searched)
    finalists = [r for r in first if r["similar"]][:cfg.select.finalists]
    say(f"{len([r for r in first if r['similar']])} program(s) similar to the validation-best "
        f"{next(r['name'] for r in first if r['best'])}; retraining {len(finalists)}: "
        + ", ".join(r["name"] for r in finalists))
    by_name = {point_name(p): p for p in points}
    retrained = run_jobs(retrain_job, [by_name[r["name"]] for r in finalists], info, jobs, "retrain",
                         name=point_name)
    final = choose(retrained)
    pick = next(r for r in final if r["picked"])
    chosen = by_name[pick["name"]]
    record = {"command": "select", "version": __version__, "task": cfg.task.name, "seed": cfg.seed,
              "budget": cfg.budget.name, "name": pick["name"], "rules": chosen.rules, "lam": chosen.lam,
              "features": chosen.features,
              "synth": {k: getattr(chosen.synth, k) for k in SEARCH_KEYS},
              "program": str(RunDir(chosen).program_file), "val_seeds": cfg.budget.val_seeds,
              "rule": "lowest mean validation loss; among programs whose paired 95% interval of the loss "
                      "difference to it contains 0, the lowest max in+out"}
    write_json(selected_file(cfg), record)  # the choice is fixed before any test episode is played
    t_select = time.perf_counter() - t0
    test = {}
    for b in ("prog", "prog-retrained"):
        c = dataclasses.replace(chosen, baseline=get(b), cmd="eval")
        test[b] = evaluate_baseline(c, RunInfo(True, info.log_dir))
    table = _table_rows(first, final)
    write_csv(RunDir(cfg).selection_file(".csv"), table)
    write_json(RunDir(cfg).selection_file(), {
        **record, "grid": {"lam": lam_grid(cfg), "rules": cfg.select.rules, "features": cfg.select.features},
        "finalists": cfg.select.finalists, "programs": first, "retrained": final,
        "test": {b: {m: s for m, s in v.items()} for b, v in test.items()},
        "seconds": {"search_and_validate": t_search, "to_choice": t_select, "total": time.perf_counter() - t0},
        "jobs": jobs, "runtime": runtime(), "config": cfg.record()})
    print_selection(table, cfg, pick["name"], test)
    say(f"[green]selected[/] {pick['name']} -> {selected_file(cfg)} ({clock(time.perf_counter() - t0)}); "
        f"`neurosym eval {run_args(cfg)} baseline=prog-retrained selected=true` and "
        f"`neurosym pipeline {run_args(cfg)} selected=true` use it")
    return {"selected": pick["name"], "loss": test["prog-retrained"]["cost"]["mean"],
            "max in-deg": test["prog-retrained"]["max_in"]["mean"]}


def _table_rows(first: list[dict], final: list[dict]) -> list[dict[str, Any]]:
    """selection.csv: one row per configuration, validation numbers of prog and (finalists) prog-retrained."""
    re = {r["name"]: r for r in final}
    rows = []
    for rank, r in enumerate(sorted(first, key=lambda r: r["loss_mean"]), start=1):
        f = re.get(r["name"])
        rows.append({
            "rank": rank, "name": r["name"], "lam": r["lam"], "rules": r["rules"], "features": r["features"],
            "objective": r["objective"], "l1": r["l1"], "degree_term": r["degree_term"],
            "val_loss": r["loss_mean"], "val_loss_ci": r["loss_ci"], "diff_to_best": r["diff"],
            "diff_ci": r["diff_ci"], "similar": r["similar"], "max_in": r["max_in"], "max_out": r["max_out"],
            "max_degree": r["degree"], "search_seconds": r["search_seconds"],
            "finalist": f is not None,
            "retrained_val_loss": None if f is None else f["loss_mean"],
            "retrained_val_loss_ci": None if f is None else f["loss_ci"],
            "retrained_similar": None if f is None else f["similar"],
            "retrained_max_degree": None if f is None else f["degree"],
            "picked": bool(f and f["picked"])})
    return rows


def print_selection(rows: list[dict], cfg: RunConfig, picked: str | None, test: dict | None) -> None:
    """The ranked table on screen (rich), the pick marked, then the pick's test numbers (``test`` None: none were
    played, as in `neurosym tune`). Rows with a ``retrain_lr`` (tune's) show it beside the features."""
    from rich.table import Table

    from ..utils.console import console

    rate = bool(rows) and "retrain_lr" in rows[0]
    t = Table(title=f"selection by validation: {cfg.task.name}, {cfg.budget.val_seeds} validation seeds "
                    f"(prog = oracle under the program; finalists retrained); ± = 95 % Student-t interval over the "
                    "validation seeds (Δ best: paired)", header_style="bold")
    for c in ("#", "lam", "K", "feat", *(("retrain lr",) if rate else ()), "objective", "val loss ± CI",
              "Δ best ± CI", "max in", "max out", "max in+out", "retrained val loss", "ret. max in+out", ""):
        t.add_column(c, justify="left" if c in ("feat", "") else "right")
    for r in rows:
        ret = "-" if r["retrained_val_loss"] is None else \
            f"{r['retrained_val_loss']:.3f} ± {r['retrained_val_loss_ci']:.3f}" + \
            ("" if r["retrained_similar"] else " (worse)")
        t.add_row(str(r["rank"]), f"{r['lam']:g}", str(r["rules"]), r["features"],
                  *((f"{r['retrain_lr']:g}",) if rate else ()), f"{r['objective']:.3f}",
                  f"{r['val_loss']:.3f} ± {r['val_loss_ci']:.3f}", f"{r['diff_to_best']:+.3f} ± {r['diff_ci']:.3f}"
                  + ("" if r["similar"] else " *"), f"{r['max_in']:.2f}", f"{r['max_out']:.2f}",
                  f"{r['max_degree']:.2f}", ret,
                  "-" if r["retrained_max_degree"] is None else f"{r['retrained_max_degree']:.2f}",
                  "[green]◀ picked[/]" if r["picked"] else ("finalist" if r["finalist"] else ""))
    console.print(t)
    console.print("* worse than the validation-best: its paired 95 % interval excludes 0. Among the finalists "
                  "(similar to the best, lowest max in+out first), the pick is the lowest max in+out whose retrained "
                  "validation loss is similar to the best retrained one.")
    console.print(LEGEND)
    if test is None:
        return
    pr = test["prog-retrained"]
    console.print(f"test ({cfg.budget.eval_seeds} seeds; ± = 95 % t-interval over the evaluation seeds of this "
                  f"one model) of {picked}: prog-retrained loss "
                  f"{pr['cost']['mean']:.3f} ± {pr['cost']['ci95']:.3f}, max in-degree {pr['max_in']['mean']:.2f}, "
                  f"max in+out {pr['max_degree']['mean']:.2f}; prog loss {test['prog']['cost']['mean']:.3f}")
