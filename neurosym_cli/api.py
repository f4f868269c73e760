"""The Python API: the verbs of the command line as functions, on the same typed config (docs/extending.md).

    import neurosym as ns

    cfg = ns.compose(task="random-grid", budget="tiny", seed=1)          # keyword overrides; dotted keys as a dict
    ns.train(cfg)                                                         # the oracle (tf-full)
    program = ns.synth(cfg)                                               # a Program (dsl/ast.py)
    ns.retrain(cfg)                                                       # prog-retrained
    metrics = ns.evaluate(cfg, "prog-retrained")                         # {metric: {mean, std, ci95, n}}
    picks = ns.picks(program, cfg, agent, rel)                            # whom each agent hears, (B, N, K)

Every function is quiet unless ``verbose=True`` (no tables, no progress lines: warnings only), returns objects,
writes the same artifacts as the command line (under ``cfg.runs_root``), and records the full typed config
beside them. Your own task: ``ns.compose(task="ring", config_dir="examples/ring/conf")``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
from pathlib import Path
from typing import Any, Iterator, Mapping

from .config import RunConfig
from .dsl.ast import Program
from .stages import RunInfo

COMMANDS = ("train", "synth", "retrain", "eval", "pipeline", "select", "tune", "show_program", "stress", "rl", "render",
            "figures", "report", "export")


def _value(v: Any) -> str:
    """A Python value as Hydra override text."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return "[" + ",".join(_value(x) for x in v) + "]"
    if v is None:
        return "null"
    return str(v)


def compose(cmd: str = "train", overrides: Mapping[str, Any] | list[str] | None = None, *,
            config_dir: str | Path | None = None, **kwargs: Any) -> RunConfig:
    """The typed config ``neurosym <cmd>`` would run with: ``compose(task="random-grid", rules=3)`` is
    ``neurosym train task=random-grid rules=3``; dotted keys go in ``overrides`` (``{"task.radius": 4.0}``, or a
    list of override strings). ``config_dir``: your own config directory (its task/ YAMLs), as ``--config-dir``.
    Bad input raises UserError with the CLI's one-line message."""
    from .commands import COMMANDS as VERBS
    from .commands.apps import compose_config
    from .errors import UserError, unknown_command

    name = VERBS[cmd][0] if cmd in VERBS else cmd
    if name not in COMMANDS:
        raise UserError(unknown_command(cmd, VERBS))
    items = list(overrides) if isinstance(overrides, list) else [f"{k}={_value(v)}" for k, v in
                                                                  {**(overrides or {})}.items()]
    items += [f"{k}={_value(v)}" for k, v in kwargs.items()]
    from .choices import check_choices, check_launcher

    extra = ["--config-dir", str(config_dir)] if config_dir else []
    bad = check_choices(items + extra) or check_launcher(items)  # the console script's lines, not Hydra's
    if bad:
        raise UserError(bad)
    return compose_config(name, items, str(config_dir) if config_dir else None)


@contextlib.contextmanager
def _quiet(verbose: bool) -> Iterator[None]:
    """No tables or progress lines unless ``verbose`` (the rich console is muted; warnings still log)."""
    from .utils.console import console, log

    if verbose:
        yield
        return
    old_quiet, old_level = console.quiet, log.level
    console.quiet, log.level = True, logging.WARNING
    try:
        yield
    finally:
        console.quiet, log.level = old_quiet, old_level


def _with(cfg: RunConfig, cmd: str, baseline: str | None) -> RunConfig:
    from .schemes import get

    cfg = dataclasses.replace(cfg, cmd=cmd, progress="plain")
    if baseline is not None:
        cfg = dataclasses.replace(cfg, baseline=get(baseline))
    if cfg.threads:
        import torch

        torch.set_num_threads(cfg.threads)
    from .utils.compiling import configure

    configure(cfg.compile, cfg.device)  # the step compiled or eager (step.py), recorded in runtime
    return cfg


def _selected(cfg: RunConfig) -> RunConfig:
    if cfg.selected:
        from .stages.select import apply_selected

        return apply_selected(cfg)
    return cfg


def _picked(cfg: RunConfig, verb: str) -> RunConfig:
    """A program baseline (prog's or det-prog's family) under the pipeline's pick among its front when there is one
    and no program= is given, as the command line does (stages/front_select.apply_front_pick)."""
    from .stages.front_select import apply_front_pick

    return apply_front_pick(cfg, verb)


TRAINED = ("checkpoint", "steps", "rollouts", "loss", "seconds")
"""the keys of what train and retrain return (_trained)"""


def _trained(cfg: RunConfig, remake: str) -> dict:
    """What train and retrain return, read from the model's manifest.json (also when it was trained before):
    checkpoint (str, the model.pt path), steps (optimizer steps), rollouts (training rollouts), loss (the final
    training loss: mean of the last steps, up to 5) and seconds (training time of the run that finished it);
    ``remake``: the command that writes the manifest again."""
    from .run import RunDir
    from .utils.io import read_json

    m = read_json(RunDir(cfg).manifest_file, remake,
                  lambda m: isinstance(m, dict) and all(k in m for k in ("checkpoint", "steps", "rollouts",
                                                                         "final_loss", "seconds_this_run")))
    return dict(zip(TRAINED, (m["checkpoint"], m["steps"], m["rollouts"], m["final_loss"], m["seconds_this_run"])))


def train(cfg: RunConfig, baseline: str | None = None, verbose: bool = False) -> dict:
    """Train the oracle (``cfg.baseline``, tf-full by default) or a baseline's own model (dist, no-comm, rl);
    resumes an interrupted run, and a trained model is kept. Returns {checkpoint: the model.pt path, steps:
    optimizer steps, rollouts: training rollouts, loss: final training loss (mean of the last steps, up to 5),
    seconds: training time of the run that finished it} (``TRAINED``, from its manifest.json)."""
    from .run import train_command
    from .stages.train import train as run

    c = _with(_selected(cfg), "train", baseline)
    with _quiet(verbose):
        run(c, RunInfo(multirun=not verbose))
    return _trained(c, train_command(c))


def synth(cfg: RunConfig, baseline: str | None = None, verbose: bool = False) -> Program | None:
    """Synthesize the program of ``cfg`` (prog, or det-prog; dt fits a tree and returns None) on the oracle's
    dataset, or reuse the one there. Returns the program."""
    from .dsl.files import load_program
    from .run import RunDir, synth_command
    from .stages.synth import synthesize

    c = _with(_selected(cfg), "synth", baseline or ("prog" if cfg.baseline.name == "tf-full" else None))
    with _quiet(verbose):
        synthesize(c, RunInfo(multirun=not verbose))
    return load_program(RunDir(c).program_file, synth_command(c)) if c.baseline.has_program else None


def retrain(cfg: RunConfig, baseline: str = "prog-retrained", verbose: bool = False) -> dict:
    """Retrain the oracle under the program (or tree) of ``cfg`` (paper section 3.5). Returns what ``train``
    returns, for the retrained model."""
    from .run import retrain_command
    from .stages.train import retrain as run

    c = _with(_selected(cfg), "retrain", baseline)
    with _quiet(verbose):
        run(c, RunInfo(multirun=not verbose))
    return _trained(c, retrain_command(c))


def evaluate(cfg: RunConfig, baseline: str | None = None, verbose: bool = False) -> dict:
    """Evaluate a baseline on the test seeds (``budget.eval_seeds``); returns its summary: metric -> mean, std,
    ci95 (a 95 % interval over the evaluation seeds of this one trained model), n."""
    from .stages.evaluate import evaluate_baseline

    with _quiet(verbose):
        return evaluate_baseline(_picked(_with(_selected(cfg), "eval", baseline), "eval"),
                                 RunInfo(multirun=not verbose))


def pipeline(cfg: RunConfig, verbose: bool = False) -> dict:
    """Every stage of ``cfg.baselines`` (train, synth, retrain, eval), reusing what exists. From Python the stages
    run in this process unless ``pipeline.jobs`` asks for more (its 0, one per core, means 1 here): worker processes
    import the calling script again, which must then keep its work under ``if __name__ == "__main__":``."""
    from .stages.pipeline import run_pipeline

    if cfg.pipeline.jobs == 0:
        cfg = dataclasses.replace(cfg, pipeline=dataclasses.replace(cfg.pipeline, jobs=1))
    cfg = dataclasses.replace(_with(cfg, "pipeline", None), progress=cfg.progress)  # threads, compile in effect
    with _quiet(verbose):
        return run_pipeline(cfg, RunInfo(multirun=not verbose))


def export(cfg: RunConfig, baseline: str | None = None, check: bool = False, verbose: bool = False) -> dict:
    """`neurosym export`: the baseline's program (JSON, Python, C), policy (TorchScript, .pt2, ONNX: export.formats)
    and golden vectors into <exp_dir>/export/<label>/ (``cfg.export.dir``); ``check=True`` replays an export in a
    process without neurosym and raises UserError naming the first mismatch. Returns what was written, or the
    check's report."""
    from .stages.export import export as run

    c = _picked(_with(cfg, "export", baseline), "export")
    c = dataclasses.replace(c, export=dataclasses.replace(c.export, check=check or c.export.check))
    with _quiet(verbose):
        return run(c, RunInfo(multirun=not verbose))


def load_program(path: str | Path) -> Program:
    """A program file, read by the project's own parser (errors name line and column), never evaluated as code."""
    from .dsl.files import load_program as load

    return load(Path(path), None)


def task(cfg: RunConfig):
    """The task of a config (its class from ``task._target_``), for rollouts and feature maps of your own."""
    from .tasks import make_task

    return make_task(cfg.task, cfg.horizon)


def picks(program: Program, cfg: RunConfig, agent, rel, round: int = 0, seed: int = 0):
    """Whom each agent hears under ``program`` for observations you supply: ``agent`` (B, N, Ds) or (N, Ds), each
    agent's own input, and ``rel`` (B, N, N, Dp) or (N, N, Dp), o_ij = agent i's view of agent j, in the task's
    units (cfg.features names the feature map). Returns (B, N, K) (or (N, K)) long agent indices, -1 = nobody;
    random rules draw from a generator seeded with ``seed``."""
    import torch

    from .dsl.interpret import program_picks
    from .tasks.programs import check_program
    from .tasks import Rng

    t = task(cfg)
    fmap = t.features(cfg.features)
    check_program(program, cfg, "program", fmap)
    agent, rel = torch.as_tensor(agent, dtype=torch.float32), torch.as_tensor(rel, dtype=torch.float32)
    single = agent.dim() == 2
    if single:
        agent, rel = agent[None], rel[None]
    gen = torch.Generator().manual_seed(seed)
    out = program_picks(program, min(round, program.n_rounds - 1), fmap.view(agent, rel), Rng(gen))
    return out[0] if single else out


__all__ = ["compose", "evaluate", "load_program", "picks", "pipeline", "retrain", "synth", "task", "train"]
