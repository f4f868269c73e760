"""`neurosym pipeline`: every stage for every listed baseline of one (task, budget, seed), in the order of the stage
graph (``graph.plan``), then the results table. Each stage is the same library call as its own command, on the
pipeline's config with the stage's baseline, so it reuses what exists and resumes what was interrupted."""

from __future__ import annotations

import csv
import dataclasses
import time
from pathlib import Path

from ..baselines import ORACLE
from ..schemes import with_run
from ..config import RunConfig
from ..run import RunDir, pipeline_command
from ..utils.console import clock, log, say
from ..utils.io import read_json, write_json
from . import RunInfo
from .evaluate import evaluate_baseline
from .graph import Stage, plan
from .results import print_table
from .synth import synthesize
from .train import retrain, train

RUNNERS = {"train": train, "synth": synthesize, "retrain": retrain, "eval": evaluate_baseline}


FRONT_RUNS = ("prog", "prog-retrained")
"""the baselines that run under the program pipeline.select=front picks (their search is the front's)"""


def stage_config(cfg: RunConfig, info: RunInfo, stage: Stage, program: str = "") -> tuple[RunConfig, RunInfo]:
    """The pipeline's config with the stage's command and baseline (what `neurosym <verb> baseline=B` composes);
    ``program``: the file a program baseline's retrain or eval runs under (program=), "" for the searched one.
    pipeline.select=front searches prog's front (synth.front=true)."""
    b = with_run(cfg, stage.baseline)
    if stage.verb == "synth" and stage.baseline == "prog" and cfg.pipeline.select == "front":
        cfg = dataclasses.replace(cfg, synth=dataclasses.replace(cfg.synth, front=True))
    program = program if stage.verb != "synth" and b.has_program else ""
    return dataclasses.replace(cfg, cmd=stage.verb, baseline=b, program=program), RunInfo(info.multirun, info.log_dir)


def _trained_seconds(history: Path) -> float:
    """Sum of the per-step wall times in a training history (0 when there is none or it is unreadable)."""
    try:
        with open(history, newline="") as f:
            return sum(float(row["seconds"]) for row in csv.DictReader(f))
    except (OSError, KeyError, ValueError, TypeError):  # none yet, or not ours: the stage's own clock stands
        return 0.0


def run_pipeline(cfg: RunConfig, info: RunInfo) -> dict:
    """Run the plan of ``cfg.baselines``; keep each stage's wall time in pipeline_timings.json; print the table."""
    if cfg.selected:  # the paper's protocol with model selection: the pick's rules, lam, features
        from .select import apply_selected, run_selection, selected_file

        if not selected_file(cfg).exists():
            train(*stage_config(cfg, info, Stage("train", ORACLE)))
            run_selection(cfg, info)
        cfg = apply_selected(cfg)
        say(f"pipeline with the selected configuration: rules={cfg.rules} lam={cfg.lam:g} features={cfg.features}")
    stages = plan(cfg.baselines)
    results = {}
    # wall time of each stage (s); a stage that reused its artifact keeps the time it first took
    timing_file = RunDir(cfg).timings_file
    timings = read_json(timing_file, pipeline_command(cfg), lambda t: isinstance(t, dict) and all(
        isinstance(v, (int, float)) for v in t.values())) if timing_file.exists() else {}
    t0 = time.perf_counter()

    def run(stage: Stage, program: str = "") -> dict:
        """One stage on the pipeline's config (``program``: a program baseline's file), its wall time kept."""
        stage_cfg, stage_info = stage_config(cfg, info, stage, program)
        # stages print no intermediate tables or live views' final renders; the pipeline prints the final table
        stage_info.multirun = info.multirun or stage.verb == "eval"
        start = time.perf_counter()
        result = RUNNERS[stage.verb](stage_cfg, stage_info)
        took = time.perf_counter() - start
        if stage.verb in ("train", "retrain"):  # the optimizer steps' own clock survives interruptions and resumes
            took = max(took, _trained_seconds(RunDir(stage_cfg).history_file))
        # a reused artifact takes ~0 s: keep the time it took to make (evaluation always reruns)
        name = stage.name + (f" {Path(stage_cfg.program).stem}" if stage_cfg.program else "")  # a pick's own
        timings[name] = round(took if stage.verb == "eval" else max(took, timings.get(name, 0.0)), 1)
        write_json(timing_file, timings)
        return result

    chosen = ""
    if cfg.pipeline.select == "front" and any(b in FRONT_RUNS for b in cfg.baselines):
        from .front_select import select_front

        chosen = str(select_front(cfg, run))
    elif cfg.pipeline.select == "front":
        log.warning("pipeline.select=front: neither prog nor prog-retrained is in baselines, nothing runs under a "
                    "program; the front is not chosen among")
    for k, stage in enumerate(stages, start=1):
        log.info("pipeline stage %d/%d: %s (%s elapsed)", k, len(stages), stage.name,
                 clock(time.perf_counter() - t0))
        results[f"{stage.verb}:{stage.baseline}"] = run(stage, chosen if stage.baseline in FRONT_RUNS else "")
    print_table(cfg, program=chosen)
    from ..config import UserError
    from .render import make_figures

    try:  # the paper's pictures of whom agents talk to, from what was just made (a few seconds)
        if cfg.plots:  # of the program prog-retrained ran under (the front's pick, under pipeline.select=front)
            make_figures(dataclasses.replace(cfg, program=chosen) if chosen else cfg, info)
    except UserError as e:
        log.warning("figures not drawn: %s", e)
    say(f"[green]pipeline done[/]: {len(stages)} stages for {cfg.task.name} ({cfg.budget.name} budget, "
        f"seed {cfg.seed}) in {clock(time.perf_counter() - t0)}")
    return results
