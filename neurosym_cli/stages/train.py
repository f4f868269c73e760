"""Train a model into its run directory, resuming from its checkpoint: the oracle or a baseline's own model
(`neurosym train`, paper section 3.1), or the oracle retrained under a program or tree (`neurosym retrain`,
section 3.5). Both use the one training loop of ``training.fit``."""

from __future__ import annotations

import dataclasses
import platform
import time
from typing import Callable

import torch

from .. import __version__
from ..config import ConfigError, RunConfig
from ..utils.io import ArtifactError, csv_bytes, write_json, write_together
from ..schemes import with_run
from ..tasks import make_task, probe
from ..policy import CommTransformer
from ..policy.comm import CommProvider, comm_module
from ..run import RunDir, train_command
from ..run.checkpoints import (checkpoint_bytes, load_checkpoint, open_checkpoint, policy_from_payload, policy_payload,
                               refuse_other_modes)
from ..run.remake import missing_chain
from ..run.models import baseline_comm, check_memory, comm_identity, load_gate
from ..training import Diverged, FitSpec, FitState, ResumeMismatch, fit
from ..utils.console import ProgressReporter, log, say, use_rich
from ..utils.cpu import runtime
from ..utils.device import resolve_device
from ..utils.lock import run_lock
from ..utils.tracking import Tracker
from ..utils.seeding import STREAM_TRAIN, generator, seed_everything
from . import RunInfo
from .tracked import open_run

class Tracked:
    """A training reporter that also hands every step's metrics to the run tracker (logger=...)."""

    def __init__(self, reporter: ProgressReporter, tracker: Tracker):
        self.reporter, self.tracker = reporter, tracker

    def update(self, step: int, total: int, metrics: dict[str, float]) -> None:
        self.reporter.update(step, total, metrics)
        self.tracker.log(step, {f"train/{k}": v for k, v in metrics.items() if k != "step"})


SEARCH_ONLY = frozenset({"lam", "objective"})
"""task fields that set the program search's defaults, not what a model is trained on (a model trained before a
task stated its objective records none, which reads as the schema's default)"""


def check_compatible(saved: dict, cfg: RunConfig, path) -> None:
    """A checkpoint is resumed or extended only under the same task, model and optimiser config, compared section
    by section against the typed config (``RunConfig.first_difference``). The message names the first differing
    key."""
    diff = cfg.first_difference(saved, ("task", "model", "optim"), SEARCH_ONLY)
    if diff:
        key, old, new = diff
        raise ConfigError(f"{path} was trained with {key}={old!r}, this run has {new!r}; pass overwrite=true to start "
                          "over or runs_root=... to train elsewhere")


def _rate_key(spec: FitSpec) -> str:
    return "optim.lr" if spec.lr is None else "optim.retrain_lr"  # train_run's callers pass retrain_lr as lr


def _rate(spec: FitSpec) -> float:
    return spec.optim.lr if spec.lr is None else spec.lr


def _kept(ckpt) -> str:
    """What a diverged run leaves: its last finite checkpoint (fit saves nothing from the bad step on)."""
    if not ckpt.exists():
        return "nothing was saved"
    try:
        payload = load_checkpoint(ckpt, "")
        step, done = payload["fit"]["step"], payload["done"]
    except Exception:  # the message is about the divergence; an unreadable old file only loses the step number
        return f"{ckpt} is kept as it was"
    return f"the last finite checkpoint (step {step}{'' if done else ', not marked trained'}) is kept at {ckpt}"


def _manifest(cfg: RunConfig, info: RunInfo, out, *, verb: str, spec: FitSpec, state: FitState, seconds: float,
              rollouts: int, device) -> tuple[list[dict], float]:
    """manifest.json of a finished training; returns (the last steps' history, their mean loss)."""
    last = state.history[-5:]  # the last (up to) five optimizer steps: one step's loss is one batch's noise
    final = sum(h["loss"] for h in last) / len(last)
    run = RunDir(cfg)
    write_json(run.manifest_file, {
        "command": verb, "version": __version__, "checkpoint": str(run.model_file), "steps": state.step,
        "rollouts": min(state.step * spec.batch, spec.rollouts), "final_loss": final,
        "final_loss_steps": len(last),
        "seconds_this_run": seconds, "rollouts_per_second": rollouts / max(seconds, 1e-9),
        "device": str(device), "torch": torch.__version__, "python": platform.python_version(),
        "hydra_dir": info.log_dir, "runtime": runtime(), "config": cfg.record(),
    })
    return last, final


def train(cfg: RunConfig, info: RunInfo) -> dict:
    """`neurosym train`: the oracle (tf-full, also the weights of hard-attn and the program baselines) with full soft
    attention, or a baseline with its own model (dist, no-comm, rl, ...) trained under its own mask; rl (paper
    appendix D) trains its gate with it, the motion by backpropagation, the decisions by policy gradient."""
    weights = cfg.baseline.weights()
    if weights.verb != "train":
        raise ConfigError(f"{cfg.baseline.name} is made by `neurosym {weights.verb}`, not `neurosym train`")
    maker = with_run(cfg, weights.baseline)  # the scheme whose model this is: tf-full's for those on the oracle
    if maker is not cfg.baseline:
        log.info("%s runs on the oracle's weights: training the oracle (tf-full)", cfg.baseline.name)
    env = make_task(cfg.task, cfg.horizon)
    # a task that breaks the protocol, or outgrows its max_agents, is one line before any training starts
    probe(env, cfg.task.name, max_agents=cfg.task.max_agents)
    seed_everything(cfg.seed)  # a provider's own parameters (rl's gate) are drawn now: from the seed, too
    comm = baseline_comm(cfg, env, scheme=maker)
    if maker.trains_from_oracle(cfg):  # from the oracle for budget.retrain_rollouts at the retraining rate
        payload = open_checkpoint(cfg, oracle=True)
        return train_run(cfg, info, env, comm, rollouts=cfg.budget.retrain_rollouts,
                         init=lambda: policy_from_payload(payload), verb="train", lr=cfg.optim.retrain_lr)
    return train_run(cfg, info, env, comm, rollouts=cfg.budget.train_rollouts,
                     init=lambda: CommTransformer.for_task(env, cfg.model), verb="train")


def retrain(cfg: RunConfig, info: RunInfo) -> dict:
    """`neurosym retrain`: every weight of the oracle fine-tuned under the program's (or tree's) hard attention;
    random rules draw from the training generator every step (section 3.5)."""
    if cfg.baseline.weights().verb != "retrain":
        raise ConfigError(f"retrain makes baseline=prog-retrained, det-prog-retrained or dt-retrained, "
                          f"not {cfg.baseline.name}")
    chain = missing_chain(cfg, "retrain")  # the oracle and the program both missing: both named at once
    if chain:
        raise ArtifactError(chain)
    env = make_task(cfg.task, cfg.horizon)
    seed_everything(cfg.seed)  # as in train: whatever the provider draws comes from the seed
    comm = baseline_comm(cfg, env)
    payload = open_checkpoint(cfg, oracle=True)
    return train_run(cfg, info, env, comm, rollouts=cfg.budget.retrain_rollouts,
                     init=lambda: policy_from_payload(payload), verb="retrain", lr=cfg.optim.retrain_lr,
                     made_under=comm_identity(cfg, comm))


def train_run(cfg: RunConfig, info: RunInfo, env, comm: CommProvider, *, rollouts: int,
              init: Callable[[], CommTransformer], verb: str, lr: float | None = None,
              made_under: str | None = None) -> dict:
    """Resume the run directory's checkpoint or start from ``init()``, fit, save.

    Writes <train_dir>/model.pt every few steps (atomically), history.csv and manifest.json. ``made_under``
    identifies the program or tree of a retraining: a checkpoint made under another one is never resumed."""
    check_memory(cfg, env, comm, training=True)  # a team that cannot fit is one line, before anything is allocated
    device = resolve_device(cfg.device)
    seed_everything(cfg.seed)
    spec = FitSpec(rollouts=rollouts, batch=cfg.budget.batch_rollouts, horizon=cfg.horizon, optim=cfg.optim, lr=lr,
                   detach_state=cfg.task.detach_state, checkpoint_every=cfg.budget.checkpoint_every,
                   comm_cost=cfg.rl.cost, shaped=cfg.rl.shaped, comm_lr_scale=cfg.rl.lr_scale)
    out = RunDir(cfg).train_dir
    with run_lock(out):
        return _train_locked(cfg, info, env, comm, init=init, verb=verb, spec=spec, device=device, out=out,
                             made_under=made_under)


def _train_locked(cfg: RunConfig, info: RunInfo, env, comm: CommProvider, *, init: Callable[[], CommTransformer],
                  verb: str, spec: FitSpec, device: torch.device, out, made_under: str | None = None) -> dict:
    run = RunDir(cfg)
    ckpt = run.model_file
    state = None
    if ckpt.exists() and not cfg.overwrite:
        payload = load_checkpoint(ckpt, train_command(cfg))
        check_compatible(payload["config"], cfg, ckpt)
        if made_under and payload.get("made_under", made_under) != made_under:
            raise ConfigError(f"{ckpt} was retrained under another program (or tree) than the one there now; "
                              "overwrite=true retrains it under this one")
        policy = policy_from_payload(payload)
        load_gate(comm, payload, ckpt, train_command(cfg))
        try:
            state = FitState(**payload["fit"])
        except TypeError:
            raise ArtifactError(f"{ckpt} has a resume state of another shape; `{train_command(cfg)} "
                                "overwrite=true` trains from the start") from None
        if state.step >= spec.steps:
            log.info("already trained: %s (%d optimizer steps); nothing to do (overwrite=true retrains)", ckpt,
                     state.step)
            if not run.manifest_file.exists():  # the run ended before its manifest (a full disk): made now
                _manifest(cfg, info, out, verb=verb, spec=spec, state=state, seconds=0.0, rollouts=0, device=device)
            return {"checkpoint": str(ckpt), "steps": state.step}
        refuse_other_modes(payload, ckpt, steps=state.step, cfg=cfg)
        log.info("resuming %s from step %d/%d (%d rollouts done)", ckpt, state.step, spec.steps,
                 state.step * spec.batch)
    else:
        policy = init()
    policy.to(device)
    gate = comm_module(comm)
    if gate is not None:
        gate.to(device)

    def save(st: FitState) -> None:
        fit_dict = dataclasses.asdict(st)  # every field a resume needs (training.FitState)
        payload = policy_payload(policy, cfg.model, cfg.record(), fit_dict, done=st.step >= spec.steps)
        if made_under:
            payload["made_under"] = made_under
        if gate is not None:
            payload["comm_state"] = gate.state_dict()
        write_together({ckpt: checkpoint_bytes(payload), run.history_file: csv_bytes(st.history)})

    label = f"{verb} {cfg.task.name} {run.model_name} seed{cfg.seed}"
    log.info("%s: %d rollouts, %d per step, T=%d, device %s -> %s", label, spec.rollouts, spec.batch,
             spec.horizon, device, out)
    steps_before = state.step if state else 0
    with open_run(cfg, stage=verb, run=f"{verb}-{run.model_name}", start=steps_before) as tracker:
        t0 = time.perf_counter()
        with ProgressReporter(label, use_rich(cfg.progress, info.multirun), cfg.budget.log_every) as rep:
            try:
                state = fit(policy, env, comm, spec, gen=generator(cfg.seed, STREAM_TRAIN), device=device,
                            reporter=Tracked(rep, tracker), save=save, state=state)
            except ResumeMismatch as e:
                raise ArtifactError(f"{ckpt}: {e}; `{train_command(cfg)} overwrite=true` trains from the "
                                    "start") from None
            except Diverged as e:
                if steps_before == 0 and e.step == 1:  # before any update: the rate played no part, the task did
                    raise ConfigError(f"{e}, before any update, so not from the learning rate: task "
                                      f"{cfg.task.name}'s cost or dynamics give non-finite values on the first "
                                      "rollout; check its cost() and step() (and task.dt, task.v_max); nothing was "
                                      "saved") from None
                raise ConfigError(f"{e}; {_kept(ckpt)}; lower {_rate_key(spec)} (now {_rate(spec):g}), or check "
                                  "the task's scales (task.dt, task.v_max), then re-run with overwrite=true") from None
        seconds = time.perf_counter() - t0
        rollouts = (state.step - steps_before) * spec.batch
        last, final = _manifest(cfg, info, out, verb=verb, spec=spec, state=state, seconds=seconds,
                                rollouts=rollouts, device=device)
        tracker.summary({"train/final_loss": final, "train/steps": state.step, "train/seconds": seconds})
        for f in (run.history_file, run.manifest_file):
            tracker.artifact(f)
    averaged = "the last step" if len(last) == 1 else f"the last {len(last)} of {state.step} steps"
    say(f"[green]done[/] {label}: training loss {final:.3f} (mean of {averaged}), {rollouts} rollouts in "
        f"{seconds:.0f} s ({rollouts / max(seconds, 1e-9):.1f} rollouts/s) -> {ckpt}")
    return {"checkpoint": str(ckpt), "steps": state.step, "loss": final}
