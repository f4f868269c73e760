"""The tracked run of a stage (``logger=``, utils/tracking.py): one per stage of one baseline of one (task, budget,
training seed), tagged with them, its config as parameters. Train, synth and eval open one each; the pipeline's
pictures go to one run of their own (``track_files``)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from ..config import RunConfig, UserError
from ..run import RunDir
from ..utils.tracking import FILES, TrackedRun, Tracker, flatten, open_tracker, trackers


def open_run(cfg: RunConfig, *, stage: str, run: str, start: int = 0, label: str | None = None) -> Tracker:
    """The trackers of ``cfg.logger`` for ``run`` (its tensorboard folder's name, e.g. "train-oracle",
    "synth-k2-lam0.5-v1", "eval-tf-full") of the verb ``stage``; ``start``: the step a training resumes from;
    ``label``: the baseline's name in the results when not its own (rl's picks)."""
    rd = RunDir(cfg)
    root = Path(cfg.runs_root)
    try:
        where = Path(cfg.exp_dir).resolve().relative_to(root.resolve()).as_posix()  # <task dir>/<budget>/seed<S>
    except ValueError:  # not under the runs root once links resolve (the config checks the written paths)
        where = Path(cfg.exp_dir).name
    if label is None:
        try:
            label = rd.label
        except UserError:  # a baseline named by a file it cannot read now: its scheme names it
            label = cfg.baseline.name
    tags = {"task": cfg.task.name, "budget": cfg.budget.name, "baseline": label, "scheme": cfg.baseline.name,
            "seed": str(cfg.seed), "stage": stage}
    return open_tracker(cfg.logger, TrackedRun(key=f"{where}/{run}", tags=tags, params=flatten(cfg.record()),
                                               tensorboard=rd.tensorboard_dir(run), store=root, start=start))


def track_files(cfg: RunConfig, files: list[Path], *, run: str = "figures") -> None:
    """Send ``files`` (those that exist) to the trackers of ``cfg.logger`` that keep files, as the artifacts of one
    run ``run`` of its own (baseline "figures": the pictures of several baselines); nothing when none keeps files."""
    files = [f for f in files if f.is_file()]
    if not files or not set(trackers(cfg.logger)) & set(FILES):
        return
    only = "+".join(t for t in trackers(cfg.logger) if t in FILES)  # no empty TensorBoard run
    with open_run(dataclasses.replace(cfg, logger=only), stage=run, run=run, label=run) as tracker:
        for f in files:
            tracker.artifact(f)
