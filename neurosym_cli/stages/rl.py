"""`neurosym rl`: the paper's comparison to communication decisions as actions (appendix D).

    1. train the rl baseline (policy/gated.py) for every setting of the grid the paper tuned: the cost weight
       (rl.grid_cost), the reward form (rl.grid_shaped) and the starting point (rl.grid_init); models that exist
       are reused, so an interrupted run resumes;
    2. evaluate each on the validation seeds (never a test episode);
    3. the paper's two picks: rl1, the lowest validation loss; rl2, the lowest validation max degree (the lower
       loss on a tie), written to rl/picks.json;
    4. only then their test evaluation, as eval/rl1 and eval/rl2: the same seeds and metrics as every other
       baseline, so they join the results table, `neurosym report` and its Pareto front.
"""

from __future__ import annotations

import dataclasses
import itertools
import os
import time
from pathlib import Path
from typing import Any

from .. import __version__
from ..baselines import run_args
from ..schemes import get
from ..config import RunConfig
from ..run import RunDir
from ..degrees import LEGEND
from ..stats import mean_ci
from ..utils.console import clock, say
from ..utils.cpu import runtime
from ..utils.io import read_json, write_csv, write_json
from . import RunInfo
from .jobs import quiet_job, run_jobs
from .validation import validate


def grid(cfg: RunConfig) -> list[RunConfig]:
    """One rl config per setting (rl.grid_init x rl.grid_shaped x rl.grid_cost), in that order."""
    return [dataclasses.replace(cfg, cmd="train", baseline=get("rl"),
                                rl=dataclasses.replace(cfg.rl, cost=c, shaped=s, init=i))
            for i, s, c in itertools.product(cfg.rl.grid_init, cfg.rl.grid_shaped, cfg.rl.grid_cost)]


def setting_name(cfg: RunConfig) -> str:
    """A setting's model name, in log lines and errors (a module-level function: the pool's workers get it pickled)."""
    return RunDir(cfg).model_name


def rl_job(cfg: RunConfig, info: RunInfo) -> dict[str, Any]:
    """One setting: its model (trained or reused), then its validation rows."""
    from .train import train

    cfg, info = quiet_job(cfg, info)
    train(cfg, info)
    manifest = read_json(RunDir(cfg).manifest_file)
    v = validate(dataclasses.replace(cfg, cmd="eval"))
    return {"name": RunDir(cfg).model_name, "cost": cfg.rl.cost, "shaped": cfg.rl.shaped, "init": cfg.rl.init,
            "loss": v["loss"], "degree": v["degree"], "degree_per_seed": v["degree_per_seed"],
            "max_in": v["max_in"], "max_out": v["max_out"], "train_loss": manifest.get("final_loss"),
            "rollouts": manifest.get("rollouts"), "train_seconds": manifest.get("seconds_this_run"),
            "rollouts_per_second": manifest.get("rollouts_per_second")}


def pick(rows: list[dict[str, Any]]) -> tuple[dict[str, Any], dict[str, Any]]:
    """(rl1, rl2): the row of lowest mean validation loss, and the row of lowest mean validation max degree (the
    lower loss on a tie), as the paper defines them (appendix D)."""
    def loss(r: dict[str, Any]) -> float:
        return sum(r["loss"]) / len(r["loss"])

    return min(rows, key=loss), min(rows, key=lambda r: (round(r["degree"], 9), loss(r)))


def picks_file(cfg: RunConfig) -> Path:
    return RunDir(cfg).picks_file


def run_rl(cfg: RunConfig, info: RunInfo) -> dict[str, Any]:
    """The whole comparison (module docstring); returns the picks and their test losses and degrees."""
    from ..run.checkpoints import open_checkpoint
    from .evaluate import evaluate_baseline

    points = grid(cfg)
    if "oracle" in cfg.rl.grid_init:  # fail early, naming the command that makes it
        open_checkpoint(cfg, oracle=True)
    jobs = cfg.rl.jobs or (os.cpu_count() or 1)
    t0 = time.perf_counter()
    say(f"rl {cfg.task.name}: {len(points)} settings (cost {cfg.rl.grid_cost}, reward to go "
        f"{cfg.rl.grid_shaped}, init {cfg.rl.grid_init}), {cfg.budget.val_seeds} validation seeds, {jobs} job(s)")
    rows = run_jobs(rl_job, points, info, jobs, "rl setting", name=setting_name)
    for r in rows:
        r["loss_mean"], r["loss_ci"] = mean_ci(r["loss"])
    rl1, rl2 = pick(rows)
    by_name = {RunDir(p).model_name: p for p in points}
    record = {"command": "rl", "version": __version__, "task": cfg.task.name, "seed": cfg.seed,
              "budget": cfg.budget.name, "val_seeds": cfg.budget.val_seeds,
              "rl1": {"name": rl1["name"], **dataclasses.asdict(by_name[rl1["name"]].rl)},
              "rl2": {"name": rl2["name"], **dataclasses.asdict(by_name[rl2["name"]].rl)},
              "rule": "rl1: lowest mean validation loss; rl2: lowest mean validation max degree (paper appendix D)"}
    write_json(picks_file(cfg), record)  # fixed before any test episode is played
    test = {}
    for label, r in (("rl1", rl1), ("rl2", rl2)):
        c = dataclasses.replace(by_name[r["name"]], cmd="eval")
        test[label] = evaluate_baseline(c, RunInfo(True, info.log_dir), label=label)
    table = [{"name": r["name"], "cost": r["cost"], "shaped": r["shaped"], "init": r["init"],
              "val_loss": r["loss_mean"], "val_loss_ci": r["loss_ci"], "max_in": r["max_in"], "max_out": r["max_out"],
              "max_degree": r["degree"], "train_loss": r["train_loss"], "rollouts": r["rollouts"],
              "train_seconds": r["train_seconds"], "rollouts_per_second": r["rollouts_per_second"],
              "pick": ",".join(lbl for lbl, x in (("rl1", rl1), ("rl2", rl2)) if x is r)} for r in rows]
    write_csv(RunDir(cfg).rl_grid_file(".csv"), table)
    write_json(RunDir(cfg).rl_grid_file(), {**record, "settings": table, "test": test,
                                            "seconds": time.perf_counter() - t0, "jobs": jobs, "runtime": runtime(),
                                            "config": cfg.record()})
    print_grid(cfg, table, test)
    say(f"[green]rl1[/] {rl1['name']}, [green]rl2[/] {rl2['name']} -> {picks_file(cfg)} "
        f"({clock(time.perf_counter() - t0)}); their test rows are eval/rl1 and eval/rl2 "
        f"(`neurosym report {run_args(cfg, seed=False)}` lists them beside the others)")
    return {"rl1": rl1["name"], "rl1 loss": test["rl1"]["cost"]["mean"], "rl2": rl2["name"],
            "rl2 loss": test["rl2"]["cost"]["mean"]}


def print_grid(cfg: RunConfig, rows: list[dict[str, Any]], test: dict) -> None:
    """The settings on screen (rich) with the picks marked, then the picks' test numbers."""
    from rich.table import Table

    from ..utils.console import console

    t = Table(title=f"rl (communication decisions as actions): {cfg.task.name}, {cfg.budget.val_seeds} validation "
                    "seeds; ± = 95 % Student-t interval over the validation seeds", header_style="bold")
    for c in ("setting", "cost", "reward", "init", "val loss ± CI", "max in", "max out", "max in+out", "rollouts/s",
              ""):
        t.add_column(c, justify="left" if c in ("setting", "reward", "init", "") else "right")
    for r in sorted(rows, key=lambda r: r["val_loss"]):
        t.add_row(r["name"], f"{r['cost']:g}", "to go" if r["shaped"] else "episode", r["init"],
                  f"{r['val_loss']:.3f} ± {r['val_loss_ci']:.3f}", f"{r['max_in']:.2f}", f"{r['max_out']:.2f}",
                  f"{r['max_degree']:.2f}", f"{r['rollouts_per_second'] or 0:.1f}",
                  f"[green]◀ {r['pick']}[/]" if r["pick"] else "")
    console.print(t)
    console.print(LEGEND)
    for label, s in test.items():
        console.print(f"test ({cfg.budget.eval_seeds} seeds; ± = 95 % t-interval over the evaluation seeds of this "
                      f"one model) {label}: loss {s['cost']['mean']:.3f} ± "
                      f"{s['cost']['ci95']:.3f}, max in-degree {s['max_in']['mean']:.2f}, max out-degree "
                      f"{s['max_out']['mean']:.2f}, max in+out {s['max_degree']['mean']:.2f}")
