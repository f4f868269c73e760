"""The paper's full protocol (budget=paper) on its three tasks, as one dependency graph of stages spread over the
machine's cores.

    python benchmarks/run_paper.py                      # all three tasks, 2 workers
    python benchmarks/run_paper.py random-grid --jobs 1  # one task, one stage at a time
    python benchmarks/run_paper.py --dry-run             # print the schedule order and the estimates

Each stage is the CLI command a user would type (`neurosym train|synth|retrain ... budget=paper baseline=B
threads=1`), so every artifact lands where `neurosym pipeline` expects it; a last `neurosym pipeline` per task
then finds all its stages done, evaluates every baseline and renders the table and figure. Workers run one torch
thread each: these small models are launch-bound, so two one-thread processes get nearly twice the throughput of
one two-thread process, and three threads on 2 cores made training 4x slower (docs/performance.md).

Scheduling is greedy by critical path: a free worker takes the ready stage with the longest estimated chain of
work still behind it (estimates from the last run's timings where they exist, else the defaults below), so the
long trainings start first and the short retrainings fill the gaps at the end. Logs go to outputs/logs/paper/;
each stage's wall time to the task's pipeline_timings.json and to outputs/logs/paper/jobs.json. Re-running the
script resumes: finished stages return at once, interrupted ones continue from their checkpoints.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from neurosym_cli.run.layout import RunFolder

from run_seeds import PAPER_METHOD  # the committed files' method (this script's folder is on sys.path)
from neurosym_cli.schemes import SCHEMES as BASELINES
from neurosym_cli.stages.graph import plan, requires

ROOT = Path(__file__).resolve().parent.parent
TASKS = ("random-cross", "random-grid", "unlabeled-goals")
# estimated one-thread seconds per stage and task, from the runs of 2026-11-25 (used when no timings exist)
DEFAULTS = {
    "train tf-full": (560, 800, 260), "train dist": (400, 540, 230), "train no-comm": (230, 300, 120),
    "synth prog": (500, 410, 300), "synth det-prog": (460, 400, 200), "synth dt": (20, 20, 80),
    "retrain prog-retrained": (60, 70, 30), "retrain det-prog-retrained": (60, 70, 30),
    "retrain dt-retrained": (110, 180, 60), "pipeline": (40, 30, 15),
}
# the stages of one task, with what each waits for: the pipeline's own stage graph (neurosym_cli/stages/graph.py)
# over every registered baseline of the paper (the follow-ups expo and comm-range are not); its evaluations are the
# last `neurosym pipeline` of each task
FOLLOW_UPS = ("expo", "comm-range")
STAGES = [s for s in plan([b for b in BASELINES if b not in FOLLOW_UPS]) if s.verb != "eval"]


@dataclass
class Job:
    task: str
    stage: str  # "train tf-full", ..., or "pipeline"
    deps: list["Job"] = field(default_factory=list)
    estimate: float = 0.0
    priority: float = 0.0  # estimate plus the longest chain of estimates that waits for this job
    seconds: float | None = None

    @property
    def name(self) -> str:
        return f"{self.task}: {self.stage}"

    def argv(self, overrides: list[str]) -> list[str]:
        common = [f"task={self.task}", "budget=paper", "threads=1", *PAPER_METHOD, *overrides]
        if self.stage == "pipeline":
            return ["neurosym", "pipeline", *common]
        cmd, baseline = self.stage.split()
        return ["neurosym", cmd, *common, f"baseline={baseline}"]


def exp_dir(task: str) -> Path:
    return ROOT / "outputs" / task / "paper" / "seed0"


def build(tasks: list[str]) -> list[Job]:
    jobs: list[Job] = []
    for task in tasks:
        col = TASKS.index(task) if task in TASKS else 0
        known = {}
        timing = RunFolder(exp_dir(task)).timings_file
        if timing.exists():
            known = json.loads(timing.read_text())
        by_stage: dict[str, Job] = {}
        for stage in STAGES:
            est = known.get(stage.name) or DEFAULTS[stage.name][col]
            by_stage[stage.name] = Job(task, stage.name, [by_stage[d.name] for d in requires(stage)], float(est))
        final = Job(task, "pipeline", list(by_stage.values()), float(DEFAULTS["pipeline"][col]))
        jobs += [*by_stage.values(), final]
    for job in reversed(jobs):  # dependants come after their dependencies: one backward pass sets priorities
        waiting = [j.priority for j in jobs if job in j.deps]
        job.priority = job.estimate + max(waiting, default=0.0)
    return jobs


def record(job: Job) -> None:
    """Write a finished stage's wall time to its task's pipeline_timings.json, unless the stage only found its
    artifact done (a few seconds), which keeps the time it took to make."""
    path = RunFolder(exp_dir(job.task)).timings_file
    timings = json.loads(path.read_text()) if path.exists() else {}
    if job.stage == "pipeline" or (job.seconds or 0.0) < 5 and job.stage in timings:
        return
    timings[job.stage] = round(job.seconds or 0.0, 1)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(timings, indent=2) + "\n")
    tmp.replace(path)


FOLLOWUPS = {  # the two extra searches of docs/results.md, run after the protocol when --followups is given
    "random-grid": ["lam=0.2", "baselines=[prog,prog-retrained,det-prog,det-prog-retrained]"],
    "unlabeled-goals": ["synth.objective=hinge", "baselines=[prog,prog-retrained]"],
}


def run_followups(tasks: list[str], logs: Path) -> None:
    """Both follow-up pipelines at once (one thread each); the protocol's stage timings are kept as they were."""
    todo = [t for t in tasks if t in FOLLOWUPS]
    saved = {t: RunFolder(exp_dir(t)).timings_file.read_text() for t in todo
             if RunFolder(exp_dir(t)).timings_file.exists()}
    # this script is the scheduler: each pipeline it starts runs its own stages one after the other
    env = dict(os.environ, OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", NEUROSYM_PIPELINE_JOBS="1")
    procs, t0 = {}, time.time()
    for t in todo:
        argv = ["neurosym", "pipeline", f"task={t}", "budget=paper", "threads=1", *PAPER_METHOD, *FOLLOWUPS[t]]
        procs[t] = subprocess.Popen(argv, stdout=open(logs / f"{t}-followup.log", "w"), stderr=subprocess.STDOUT,
                                    cwd=ROOT, env=env)
    took = {}
    for t, p in procs.items():
        rc = p.wait()
        took[t] = {"seconds": round(time.time() - t0, 1), "exit": rc, "overrides": FOLLOWUPS[t]}
        print(f"follow-up {t} ({' '.join(FOLLOWUPS[t])}): exit {rc} after {took[t]['seconds'] / 60:.1f} min")
    for t, text in saved.items():
        RunFolder(exp_dir(t)).timings_file.write_text(text)
    (logs / "followups.json").write_text(json.dumps(took, indent=2) + "\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("tasks", nargs="*", default=list(TASKS))
    ap.add_argument("--jobs", type=int, default=2, help="stages run at once (one torch thread each)")
    ap.add_argument("--dry-run", action="store_true")
    ap.add_argument("--followups", action="store_true", help="then the follow-up searches of docs/results.md")
    ap.add_argument("overrides", nargs=argparse.REMAINDER, help="after --: Hydra overrides for every stage")
    a = ap.parse_args()
    overrides = [o for o in a.overrides if o != "--"]
    jobs = build(a.tasks)
    logs = ROOT / "outputs" / "logs" / "paper"
    logs.mkdir(parents=True, exist_ok=True)
    if a.dry_run:
        for j in sorted(jobs, key=lambda j: -j.priority):
            print(f"{j.priority:7.0f} {j.estimate:6.0f}  {j.name}  <- {', '.join(d.stage for d in j.deps) or '-'}")
        print(f"total estimate {sum(j.estimate for j in jobs) / 60:.0f} core-min")
        return
    # this script is the scheduler: each pipeline it starts runs its own stages one after the other
    env = dict(os.environ, OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", NEUROSYM_PIPELINE_JOBS="1")
    pending = list(jobs)
    running: dict[subprocess.Popen, tuple[Job, float]] = {}
    start = time.time()
    failed: list[str] = []
    while pending or running:
        ready = [j for j in pending if all(d.seconds is not None for d in j.deps)]
        while ready and len(running) < a.jobs:
            job = max(ready, key=lambda j: j.priority)
            ready.remove(job)
            pending.remove(job)
            log = open(logs / f"{job.task}-{job.stage.replace(' ', '-')}.log", "w")
            proc = subprocess.Popen(job.argv(overrides), stdout=log, stderr=subprocess.STDOUT, cwd=ROOT, env=env)
            running[proc] = (job, time.time())
            print(f"[{(time.time() - start) / 60:5.1f} min] start {job.name}", flush=True)
            time.sleep(1.1)  # Hydra names a run directory by command and second: never two in one second
        if not running:  # what is left waits on a failed stage
            failed += [j.name for j in pending]
            break
        time.sleep(1.0)
        for proc in [p for p in running if p.poll() is not None]:
            job, t0 = running.pop(proc)
            if proc.returncode != 0:
                failed.append(job.name)
                print(f"[{(time.time() - start) / 60:5.1f} min] FAILED {job.name} (exit {proc.returncode}); "
                      f"see outputs/logs/paper/", flush=True)
                job.seconds = None
                pending = [j for j in pending if job not in j.deps]
                failed += [j.name for j in jobs if job in j.deps]
                continue
            job.seconds = time.time() - t0
            record(job)
            print(f"[{(time.time() - start) / 60:5.1f} min] done  {job.name} in {job.seconds:.0f} s", flush=True)
    wall = time.time() - start
    summary = {"tasks": a.tasks, "jobs": a.jobs, "wall_s": round(wall, 1), "failed": failed,
               "stages": {j.name: None if j.seconds is None else round(j.seconds, 1) for j in jobs}}
    (logs / "jobs.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(f"all stages: {wall / 60:.1f} min wall on {a.jobs} workers; "
          f"{sum(j.seconds or 0 for j in jobs) / 60:.1f} worker-min", flush=True)
    if failed:
        print("failed or skipped: " + ", ".join(dict.fromkeys(failed)), file=sys.stderr)
        raise SystemExit(1)
    if a.followups:
        run_followups(a.tasks, logs)


if __name__ == "__main__":
    main()
