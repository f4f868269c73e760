"""The command lines that make (or make again) an artifact of a run directory: what error messages tell the user to
run (stdlib only). Each comes from the baseline's scheme (``cfg.baseline.command``), which knows its own stages."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..baselines import ORACLE, Stage, run_args, train_line

if TYPE_CHECKING:
    from ..config import RunConfig


def train_command(cfg: "RunConfig", oracle: bool = False) -> str:
    """The command line that makes the weights ``cfg``'s baseline needs (or the oracle's)."""
    return train_line(cfg, ORACLE) if oracle else cfg.baseline.weights_command(cfg)


def retrain_command(cfg: "RunConfig") -> str:
    """The command line that retrains ``cfg``'s (retrained) baseline."""
    return cfg.baseline.command("retrain", cfg)


def synth_command(cfg: "RunConfig") -> str:
    """The command line that synthesizes the program or tree ``cfg``'s baseline runs under."""
    return cfg.baseline.command("synth", cfg)


def show_command(cfg: "RunConfig") -> str:
    """The command line that prints the program ``cfg``'s baseline's search makes, and its degree-budget front
    (show-program with the search's task, K, lambda, features, settings, seed and runs root: it runs as printed)."""
    return "neurosym show-program " + synth_command(cfg).split(" ", 2)[2]


def pipeline_command(cfg: "RunConfig") -> str:
    """The command line that makes (or reuses) every artifact of ``cfg``'s run directory and evaluates again."""
    return f"neurosym pipeline {run_args(cfg)}"


def _made(cfg: "RunConfig", stage: Stage) -> bool:
    """Whether the artifact ``stage`` makes for ``cfg``'s run directory is on disk (a model or a program or tree;
    ``program=`` stands for the search's). What cannot be named here its own reader reports: counted as made."""
    import dataclasses

    from ..errors import UserError
    from ..schemes import with_run
    from .layout import RunDir

    try:
        run = RunDir(dataclasses.replace(cfg, baseline=with_run(cfg, stage.baseline)))
        file = run.artifact_file() if stage.verb == "synth" else run.model_file
    except UserError:
        return True
    return file is None or file.exists()


def needed_stages(cfg: "RunConfig", verb: str = "eval") -> list[Stage]:
    """Every stage ``cfg.baseline``'s ``verb`` (its evaluation, or one of its own stages) waits for, each before
    the stages that wait for it."""
    from ..schemes import with_run

    out: list[Stage] = []

    def add(stage: Stage) -> None:
        for before in with_run(cfg, stage.baseline).requires(stage.verb):
            add(before)
        if stage not in out:
            out.append(stage)

    for stage in cfg.baseline.upstream() if verb == "eval" else cfg.baseline.requires(verb):
        add(stage)
    return out


def missing_chain(cfg: "RunConfig", verb: str = "eval") -> str | None:
    """One line naming, in order, the command of every stage ``cfg.baseline``'s ``verb`` needs whose artifact is
    not on disk, and the one pipeline that runs them all, when two or more are missing (each reader named only the
    stage just before it: retrain, then synth, then train); None otherwise (the one missing artifact's reader names
    its command)."""
    import shlex

    from ..schemes import with_run

    needed = needed_stages(cfg, verb)
    missing = [s for s in needed if not _made(cfg, s)]
    if len(missing) < 2:
        return None
    lines = [with_run(cfg, s.baseline).command(s.verb, cfg) for s in missing]
    last = with_run(cfg, needed[-1].baseline).command(needed[-1].verb, cfg)  # carries the baseline's settings
    # the searched program itself: pipeline.select=front would run a program baseline under the front's pick
    # (another label and retrained model), never making what this command needs
    own = " pipeline.select=none" if cfg.baseline.has_program and cfg.pipeline.select != "none" else ""
    pipeline = ("neurosym pipeline " + last.split(" ", 2)[2] + own + " "
                + shlex.quote(f"baselines=[{cfg.baseline.name}]"))
    what = f"{cfg.baseline.name}" if verb == "eval" else f"{verb} of {cfg.baseline.name}"
    return (f"{what} needs {len(missing)} stages that have not run in {cfg.exp_dir}: "
            + ", then ".join(f"`{line}`" for line in lines) + f"; or `{pipeline}` runs them all and evaluates it")
