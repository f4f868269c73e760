"""`neurosym pipeline`: every stage for every listed baseline of one (task, budget, seed), as the stage graph
(``graph.plan``) allows, pipeline.jobs at once (stages/flow.py), then the results table. Each stage is the same library call as its own command, on the
pipeline's config with the stage's baseline, so it reuses what exists and resumes what was interrupted."""

from __future__ import annotations

import csv
import dataclasses
import os
import time
from pathlib import Path
from typing import Any

from ..baselines import ORACLE
from ..schemes import get, with_run
from ..config import RunConfig, UserError
from ..run import RunDir, pipeline_command
from ..utils.console import clock, left_text, log, say
from ..utils.io import read_json, write_json
from . import RunInfo
from .evaluate import evaluate_baseline
from .flow import Flow, Job, Node, Worker, one, run_flow
from .front_select import (PROG, SILENT_BASELINE, Validated, choose_front, family_of, fronted, validated_front,
                           validation)
from .graph import Stage, plan, requires
from .jobs import quiet_job
from .results import print_table
from .synth import collect_dataset, searched, synthesize
from .tracked import track_files
from .train import retrain, train

RUNNERS = {"train": train, "synth": synthesize, "retrain": retrain, "eval": evaluate_baseline}


def stage_config(cfg: RunConfig, info: RunInfo, stage: Stage, program: str = "") -> tuple[RunConfig, RunInfo]:
    """The pipeline's config with the stage's command and baseline (what `neurosym <verb> baseline=B` composes);
    ``program``: the file a program baseline's retrain or eval runs under (program=), "" for the searched one.
    pipeline.select=front searches the front of each family it picks for (synth.front=true)."""
    b = with_run(cfg, stage.baseline)
    if stage.verb == "synth" and family_of(stage.baseline) in fronted(cfg):
        cfg = dataclasses.replace(cfg, synth=dataclasses.replace(cfg.synth, front=True))
    program = program if stage.verb != "synth" and b.has_program else ""
    return dataclasses.replace(cfg, cmd=stage.verb, baseline=b, program=program), RunInfo(info.multirun, info.log_dir)


WEIGHTS = {"train": 1.0, "retrain": 1.0, "synth": 0.05, "eval": 1.5}
"""rough seconds of one unit of a verb's work (stage_units), in seconds of one training rollout (the quick and paper
budgets' pipeline_timings.json: a retraining rollout costs about what a training one does, a search step about a
twentieth, an evaluation seed one and a half): what the time left assumes for a verb none of whose stages has run"""


def stage_units(cfg: RunConfig, stage: Stage) -> float:
    """The work of one stage of ``cfg``'s plan in its verb's units: training or retraining rollouts, search steps
    (all rounds), evaluation seeds; 0 for a stage whose artifact is there already (a finished training's manifest,
    a finished search: stages/synth.searched; it is reused, unless overwrite=true; an evaluation always runs)."""
    b = cfg.budget
    try:
        if not cfg.overwrite and stage.verb != "eval" and \
                (searched(cfg) if stage.verb == "synth" else RunDir(cfg).manifest_file.exists()):
            return 0.0  # overwrite=true makes it again
    except (UserError, OSError):  # a program file not there yet: the stage will say so; count its work
        pass
    return {"train": b.train_rollouts, "retrain": b.retrain_rollouts, "synth": b.mcmc_steps * cfg.task.rounds,
            "eval": b.eval_seeds}[stage.verb]


class PipelineClock:
    """The pipeline's time left: each remaining stage's units (stage_units) at the seconds per unit measured on this
    run's stages of the same verb; else the time the same stage took when this run directory's pipeline last ran
    it (pipeline_timings.json); else the pace of the verbs measured so far scaled by WEIGHTS. A stage that took
    under a second (a reused artifact) measures nothing; None while a stage has none of these."""

    def __init__(self) -> None:
        self.spent: dict[str, tuple[float, float]] = {}  # verb -> (seconds, units) of its stages that did work

    def done(self, verb: str, units: float, seconds: float) -> None:
        if units > 0 and seconds >= 1.0:
            s, u = self.spent.get(verb, (0.0, 0.0))
            self.spent[verb] = (s + seconds, u + units)

    def rate(self, verb: str) -> float | None:
        """Seconds per unit of ``verb``'s work."""
        if verb in self.spent:
            s, u = self.spent[verb]
            return s / u
        if not self.spent:
            return None
        per_weight = sum(s for s, _ in self.spent.values()) / sum(u * WEIGHTS[v] for v, (_, u) in self.spent.items())
        return per_weight * WEIGHTS[verb]

    def left(self, remaining: list[tuple[str, float, float | None]]) -> float | None:
        """Seconds left for the stages still to run, each (verb, units, the seconds it took before or None)."""
        total = 0.0
        for verb, units, before in remaining:
            if units <= 0:
                continue
            rate = self.rate(verb) if verb in self.spent or before is None else None
            if rate is None and before is None:
                return None
            total += units * rate if rate is not None else before
        return total


def timing_name(stage: Stage, cfg: RunConfig) -> str:
    """A stage's key in pipeline_timings.json: its name, and the program it runs under (a front pick's own)."""
    return stage.name + (f" {Path(cfg.program).stem}" if cfg.program else "")


def _trained_seconds(history: Path) -> float:
    """Sum of the per-step wall times in a training history (0 when there is none or it is unreadable)."""
    try:
        with open(history, newline="") as f:
            return sum(float(row["seconds"]) for row in csv.DictReader(f))
    except (OSError, KeyError, ValueError, TypeError):  # none yet, or not ours: the stage's own clock stands
        return 0.0


@dataclasses.dataclass(frozen=True)
class StageRun:
    """What one stage's job hands back to the pipeline: its ``verb``, key in pipeline_timings.json (``name``), work
    (stage_units), wall time (s) and the stage's own result."""

    verb: str
    name: str
    units: float
    took: float
    result: Any


def run_stage(cfg: RunConfig, info: RunInfo, stage: Stage, program: str = "") -> StageRun:
    """One stage on the pipeline's config (``program``: a program baseline's file), timed: a pipeline's job, in its
    process or a worker's."""
    stage_cfg, stage_info = stage_config(cfg, info, stage, program)
    # stages print no intermediate tables or live views' final renders; the pipeline prints the final table
    stage_info.multirun = info.multirun or stage.verb == "eval"
    units = stage_units(stage_cfg, stage)
    start = time.perf_counter()
    result = RUNNERS[stage.verb](stage_cfg, stage_info)
    took = time.perf_counter() - start
    if stage.verb in ("train", "retrain"):  # the optimizer steps' own clock survives interruptions and resumes
        took = max(took, _trained_seconds(RunDir(stage_cfg).history_file))
    return StageRun(stage.verb, timing_name(stage, stage_cfg), units, took, result)


def pipeline_jobs(cfg: RunConfig) -> int:
    """Stages at once: pipeline.jobs, or (0) one per CPU core this process may use over ``threads`` each; one on a
    GPU (one device) or with threads=0 (every core for one stage)."""
    if cfg.pipeline.jobs:
        return cfg.pipeline.jobs
    from ..utils.device import resolve_device

    if cfg.threads == 0 or resolve_device(cfg.device).type != "cpu":
        return 1
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, cores // cfg.threads)


CANDIDATES_GUESS = 4
"""front candidates assumed by the time left before the front is read and no earlier run timed them (a two-rule
front's distinct programs and nearest-within-r ones: 3 to 6 on the main job's seeds)"""


def dataset_key(path: Path) -> str:
    """The graph's key of the node that collects the oracle dataset ``path``."""
    return f"collect D {path.name}"


def collect(cfg: RunConfig) -> StageRun:
    """The oracle dataset D of ``cfg`` (a search's config), collected or found (stages/synth.collect_dataset), as a
    pipeline job: its searches then start together and reuse it."""
    start = time.perf_counter()
    collect_dataset(cfg)
    path = RunDir(cfg).dataset_file
    return StageRun("dataset", dataset_key(path), 0.0, time.perf_counter() - start, str(path))


def waits(stage: Stage, stages: list[Stage]) -> list[Stage]:
    """The stages of ``stages`` that ``stage`` waits for: its requirements, and where one is not in the list (a
    search program= makes unnecessary) what that one waits for, and so on."""
    out: list[Stage] = []
    for r in requires(stage):
        for w in [r] if r in stages else waits(r, stages):
            if w not in out:
                out.append(w)
    return out


def run_pipeline(cfg: RunConfig, info: RunInfo) -> dict:
    """Run the plan of ``cfg.baselines``, pipeline.jobs stages at once as the stage graph allows (stages/flow.py);
    keep each stage's wall time in pipeline_timings.json; print the table."""
    if cfg.selected:  # the paper's protocol with model selection: the pick's rules, lam, features
        from .select import apply_selected, run_selection, selected_file

        if not selected_file(cfg).exists():
            train(*stage_config(cfg, info, Stage("train", ORACLE)))
            run_selection(cfg, info)
        cfg = apply_selected(cfg)
        say(f"pipeline with the selected configuration: rules={cfg.rules} lam={cfg.lam:g} features={cfg.features}")
    stages = plan(cfg.baselines)
    if cfg.program:  # a hand-written program: prog and prog-retrained run under it, nothing is searched for them
        stages = [s for s in stages if s != Stage("synth", "prog")]
        say(f"pipeline: prog and prog-retrained run under program={cfg.program}")
    fams = fronted(cfg)  # the families whose program is picked among their front
    if cfg.pipeline.select == "front" and not fams and not cfg.program:
        log.warning("pipeline.select=front: no baseline of baselines runs under a searched program (prog, det-prog "
                    "and their retrainings); the front is not chosen among")
    first = ([Stage("train", ORACLE), Stage("train", SILENT_BASELINE)] + [Stage("synth", f.search) for f in fams]
             if fams else [])
    # what the front selections need goes first, listed or not: their retrainings are the longest chains
    stages = first + [s for s in stages if s not in first]
    searches = {f: RunDir(dataclasses.replace(cfg, baseline=get(f.search), program="")) for f in fams}
    chosen = {PROG.search: cfg.program}  # family -> the program its baselines run under, once known

    def program_of(stage: Stage) -> str:
        fam = family_of(stage.baseline)
        return chosen.get(fam.search, "") if fam else ""

    def waits_for_pick(stage: Stage) -> bool:
        return stage.verb != "synth" and family_of(stage.baseline) in fams

    # the stages with work left (a finished training or search is reused; an evaluation always reruns, in a
    # second); under a front, its pick's retraining is one of its candidates', done once it has chosen
    to_do = [s for s in stages if s.verb != "eval" and not waits_for_pick(s)
             and stage_units(stage_config(cfg, info, s, program_of(s))[0], s)]
    chose = all(rd.front_choice_file(rd.program_tag).exists() for rd in searches.values())
    jobs = min(pipeline_jobs(cfg), len(stages)) if to_do or not chose else 1  # nothing to make: no worker started
    job_cfg, job_info = quiet_job(cfg, info) if jobs > 1 else (cfg, info)  # workers: plain lines, no tables
    # wall time of each stage (s); a stage that reused its artifact keeps the time it first took
    timing_file = RunDir(cfg).timings_file
    timings = read_json(timing_file, pipeline_command(cfg), lambda t: isinstance(t, dict) and all(
        isinstance(v, (int, float)) for v in t.values())) if timing_file.exists() else {}
    t0 = time.perf_counter()
    pace = PipelineClock()
    made: set[str] = set()  # timing names of the stages that ran in this pipeline
    done_names: set[str] = set()  # graph keys of the nodes done
    started: dict[str, float] = {}  # stage name -> when it started
    candidates: dict[str, list[str]] = {f.search: [] for f in fams}  # each front's program files, once read

    def record(out: Any) -> None:
        """A job's result, in this process: a stage's pace and wall time (a reused artifact takes ~0 s: keep the time
        it took to make; an evaluation always reruns)."""
        if isinstance(out, StageRun):
            pace.done(out.verb, out.units, out.took)
            made.add(out.name)
            timings[out.name] = round(out.took if out.verb == "eval" else max(out.took, timings.get(out.name, 0.0)),
                                      1)
            write_json(timing_file, timings)

    def retrain_job(baseline: str, program: str) -> Job:
        return Job(run_stage, (job_cfg, job_info, Stage("retrain", baseline), program),
                   f"retrain {Path(program).stem}")

    def validate_job(baseline: str, program: str) -> Job:
        return Job(validation, (job_cfg, baseline, program), f"validate {baseline}")

    def remaining() -> list[float | None]:
        """Seconds of each piece of work not done (None: not known yet): stages not started, the running ones less
        their time so far, the fronts' retrainings."""
        out = []
        for s in stages:
            if s.name in done_names:
                continue
            c = stage_config(cfg, info, s, program_of(s))[0]
            est = pace.left([(s.verb, stage_units(c, s), timings.get(timing_name(s, c)))])
            if s.name in started and est is not None:  # running: what is left of it
                est = max(0.0, est - (time.perf_counter() - started[s.name]))
            out.append(est)
        for fam, search in searches.items():
            if fam.node in done_names:
                continue
            stage = Stage("retrain", fam.retrained)
            ours = f"{stage.name} {search.program_tag}-"  # this search's candidates in an earlier run
            guess = sum(k.startswith(ours) for k in timings) or CANDIDATES_GUESS
            for f in candidates[fam.search] or [""] * guess:
                c = stage_config(cfg, info, stage, f)[0]
                if not f or timing_name(stage, c) not in made:
                    out.append(pace.left([("retrain", stage_units(c, stage) if f else cfg.budget.retrain_rollouts,
                                           timings.get(timing_name(stage, c)) if f else None)]))
        return out

    def left_now() -> float | None:
        """Seconds left for the pipeline: its remaining work over the jobs at once, and no less than its longest
        remaining piece."""
        each = remaining()
        if any(e is None for e in each):
            return None
        return max([sum(each) / jobs, *each]) if each else 0.0

    count = iter(range(1, len(stages) + 1))

    def stage_node(stage: Stage) -> Node:
        def start() -> Flow:
            started[stage.name] = time.perf_counter()
            out = yield from one(Job(run_stage, (job_cfg, job_info, stage, program_of(stage)), stage.name))
            done_names.add(stage.name)
            return out

        def announce() -> None:
            left = left_now()
            log.info("pipeline stage %d/%d: %s (%s elapsed, %s left%s)", next(count), len(stages), stage.name,
                     clock(time.perf_counter() - t0), left_text(left),
                     "" if left is not None else ": measured once a stage has run")

        needs = [w.name for w in waits(stage, stages)]
        if waits_for_pick(stage):
            needs.append(family_of(stage.baseline).node)  # type: ignore[union-attr]
        if stage.verb == "synth":  # its dataset D, collected once for every search of the oracle
            needs.append(dataset_key(RunDir(stage_config(cfg, info, stage)[0]).dataset_file))
        return Node(stage.name, start, tuple(needs), announce)

    nodes = [stage_node(s) for s in stages]
    collecting: set[str] = set()
    datasets: dict[str, Node] = {}  # one node per dataset D the searches read, waiting for the oracle like them
    for s in stages:
        if s.verb == "synth":
            c = stage_config(job_cfg, job_info, s)[0]
            key = dataset_key(RunDir(c).dataset_file)
            if s in to_do and key not in collecting:  # D is read only by searches left to do
                collecting.add(key)
                datasets[key] = Node(key, lambda c=c: one(Job(collect, (c,), "collect D")),
                                     tuple(w.name for w in waits(s, stages)))
            datasets.setdefault(key, Node(key, lambda: iter(())))  # nothing to collect: done at once
    nodes[len(first):len(first)] = list(datasets.values())
    validated: dict[str, Validated] = {}  # each family's front, retrained and validated
    for fam in reversed(fams):
        def retrained(fam=fam) -> Flow:
            validated[fam.search] = yield from validated_front(cfg, fam, retrain_job, validate_job,
                                                               candidates[fam.search].extend)

        def selection(fam=fam) -> Flow:
            yield []  # no job: the pick is made in this process
            path = choose_front(cfg, fam, validated[fam.search], matched=fam.matches in fams)
            chosen[fam.search] = str(path)
            done_names.add(fam.node)
            return path

        needs = (Stage("train", ORACLE).name, Stage("train", SILENT_BASELINE).name, Stage("synth", fam.search).name)
        # its pick, not its retrainings, waits for the family it is read against (Family.matches)
        picks = (fam.retrained_node,) + ((fam.matches.node,) if fam.matches in fams else ())
        nodes[len(first):len(first)] = [Node(fam.retrained_node, retrained, needs), Node(fam.node, selection, picks)]
    if jobs > 1:
        say(f"pipeline: {len(stages)} stages, up to {jobs} at once (pipeline.jobs; each its own process and thread)")
    values = run_flow(nodes, jobs, worker=Worker.like_this_process(cfg), on_result=record)
    results = {f"{s.verb}:{s.baseline}": values[s.name].result for s in stages}
    print_table(cfg, program=chosen[PROG.search])
    from .render import make_figures

    figures: dict[str, str] = {}
    try:  # the paper's pictures of whom agents talk to, from what was just made (a few seconds)
        if cfg.plots:  # of the program prog-retrained ran under (the front's pick, under pipeline.select=front)
            log.info("pipeline: the figures (%s elapsed)", clock(time.perf_counter() - t0))
            mine = chosen[PROG.search]
            figures = make_figures(dataclasses.replace(cfg, program=mine) if mine else cfg, info)
    except UserError as e:
        log.warning("figures not drawn: %s", e)
    try:  # the table's plot, the training curves and the figures, to the trackers that keep files
        if cfg.plots:
            track_files(cfg, [RunDir(cfg).figure2_file, RunDir(cfg).curves_file, *map(Path, figures.values())])
    except UserError as e:  # the pipeline's work is done and on disk: a tracker's failure is a warning here
        log.warning("figures not sent to the trackers: %s", e)
    say(f"[green]pipeline done[/]: {len(stages)} stages for {cfg.task.name} ({cfg.budget.name} budget, "
        f"seed {cfg.seed}) in {clock(time.perf_counter() - t0)}")
    return results
