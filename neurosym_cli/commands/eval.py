"""`neurosym eval`: the evaluation protocol for one baseline; prints a table of every baseline evaluated so far."""

from __future__ import annotations

import time
from pathlib import Path

from .. import __version__, artifacts, paths
from ..config import RunConfig
from ..envs import make_env
from ..evaluation import evaluate, summarize
from ..plotting import figure2
from ..utils.console import console, log, metrics_table
from ..utils.device import resolve_device
from ..utils.seeding import seed_everything
from ._comm import baseline_comm
from ._run import Context

COLUMNS = [("cost", "loss"), ("max_in", "max in-deg"), ("max_out", "max out-deg"), ("mean_degree", "mean deg"),
           ("collisions", "collisions")]


def run(cfg: RunConfig, ctx: Context) -> dict:
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
    artifacts.write_csv(out / "metrics.csv", rows)
    artifacts.write_json(out / "metrics.json", {
        "baseline": cfg.baseline.name, "label": label, "task": cfg.task.name, "rules": cfg.rules,
        "seeds": len(seeds), "episodes_per_seed": rows[0]["episodes"], "summary": summary, "per_seed": rows,
        "model": str(paths.train_dir(cfg) / "model.pt"), "seconds": seconds, "version": __version__,
        "config": ctx.config_dict(),
    })
    log.info("evaluated %s on %d seeds in %.1f s -> %s", label, len(seeds), seconds, out)
    if ctx.multirun:
        write_figure(cfg)
    else:
        print_table(cfg)
    return summary


def _title(cfg: RunConfig) -> str:
    return (f"{cfg.task.name} ({cfg.budget.name} budget, train seed {cfg.seed}): "
            f"mean ± std over {cfg.budget.eval_seeds} eval seeds")


def write_figure(cfg: RunConfig) -> Path:
    """Figure-2-style PNG of every baseline evaluated in this experiment directory."""
    return figure2(collect(Path(cfg.exp_dir)), _title(cfg).replace(": ", ":\n"), Path(cfg.exp_dir) / "eval" / "figure2.png")


def print_table(cfg: RunConfig) -> None:
    """The results table of every baseline evaluated in this experiment directory, and its plot."""
    png = write_figure(cfg)
    console.print(metrics_table(_title(cfg), collect(Path(cfg.exp_dir)), COLUMNS))
    console.print(f"plot of every baseline evaluated here: {png}")


ORDER = ["tf-full", "hard-attn", "dist", "prog", "prog-retrained", "det-prog", "det-prog-retrained", "dt",
         "dt-retrained", "no-comm"]


def collect(exp_dir: Path) -> list[tuple[str, dict]]:
    """Every baseline evaluated in an experiment directory, in the paper's order."""
    found = []
    for f in sorted((exp_dir / "eval").glob("*/metrics.json")):
        m = artifacts.read_json(f)
        found.append((m["label"], m["summary"], m["baseline"]))
    found.sort(key=lambda t: (ORDER.index(t[2]) if t[2] in ORDER else len(ORDER), t[0]))
    return [(label, summary) for label, summary, _ in found]
