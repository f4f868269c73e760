"""`neurosym pipeline`: every stage for every baseline of one (task, budget, seed), then the results table.

Each stage is the same code as its own command, run on the pipeline's config with the stage's baseline, so it
reuses what exists (a trained model, a program) and resumes what was interrupted.
"""

from __future__ import annotations

import csv
import time
from importlib.resources import files
from pathlib import Path

from omegaconf import OmegaConf

from .. import paths
from ..config import ConfigError, RunConfig
from ..utils.console import console, log
from ..utils.io import read_json, write_json
from . import eval as eval_cmd
from . import retrain as retrain_cmd
from . import synth as synth_cmd
from . import train as train_cmd
from ._run import Context


def _stage(ctx: Context, cmd: str, baseline: str) -> tuple[RunConfig, Context]:
    path = files("neurosym_cli.conf").joinpath("baseline", f"{baseline}.yaml")
    if not path.is_file():
        raise ConfigError(f"unknown baseline {baseline!r} in `baselines`")
    raw = OmegaConf.merge(ctx.raw, {"cmd": cmd, "baseline": OmegaConf.load(str(path))})
    return OmegaConf.to_object(raw), Context(raw, ctx.multirun, ctx.hydra_dir)  # type: ignore[return-value]


def _trained_seconds(history: Path) -> float:
    """Sum of the per-step wall times in a training history (0 when there is none)."""
    if not history.exists():
        return 0.0
    with open(history, newline="") as f:
        return sum(float(row["seconds"]) for row in csv.DictReader(f))


def run(cfg: RunConfig, ctx: Context) -> dict:
    """Plan the stages the listed baselines need, run them in dependency order, evaluate, print the table."""
    plan: list[tuple[str, str]] = []

    def need(cmd: str, baseline: str) -> None:
        if (cmd, baseline) not in plan:
            plan.append((cmd, baseline))

    for b in cfg.baselines:
        stage_cfg, _ = _stage(ctx, "train", b)
        model = stage_cfg.baseline.model
        need("train", "tf-full")  # every program baseline and hard-attn run on the oracle
        if model == "own":
            need("train", b)
        if stage_cfg.baseline.comm == "program":
            need("synth", "det-prog" if stage_cfg.baseline.det else "prog")
        if stage_cfg.baseline.comm == "tree":
            need("synth", "dt")
        if model == "retrained":
            need("retrain", b)
    plan += [("eval", b) for b in cfg.baselines]
    runners = {"train": train_cmd.run, "synth": synth_cmd.run, "retrain": retrain_cmd.run, "eval": eval_cmd.run}
    results = {}
    # wall time of each stage (s); a stage that reused its artifact keeps the time it first took
    timing_file = Path(cfg.exp_dir) / "pipeline_timings.json"
    timings = read_json(timing_file) if timing_file.exists() else {}
    for k, (cmd, b) in enumerate(plan, start=1):
        log.info("pipeline stage %d/%d: %s %s", k, len(plan), cmd, b)
        stage_cfg, stage_ctx = _stage(ctx, cmd, b)
        # stages print no intermediate tables; the pipeline prints the final one
        quiet = Context(stage_ctx.raw, True, stage_ctx.hydra_dir) if cmd == "eval" else stage_ctx
        start = time.perf_counter()
        results[f"{cmd}:{b}"] = runners[cmd](stage_cfg, quiet)
        took = time.perf_counter() - start
        if cmd in ("train", "retrain"):  # the optimizer steps' own clock survives interruptions and resumes
            took = max(took, _trained_seconds(paths.train_dir(stage_cfg) / "history.csv"))
        key = f"{cmd} {b}"
        # a reused artifact takes ~0 s: keep the time it took to make (evaluation always reruns)
        timings[key] = round(took if cmd == "eval" else max(took, timings.get(key, 0.0)), 1)
        write_json(timing_file, timings)
    final_cfg, final_ctx = _stage(ctx, "eval", cfg.baselines[-1])
    eval_cmd.print_table(final_cfg)
    console.print(f"[green]pipeline done[/]: {len(plan)} stages for {cfg.task.name} ({cfg.budget.name} budget, "
                  f"seed {cfg.seed})")
    return results
