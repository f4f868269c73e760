"""`neurosym train`: train the oracle transformer (or a baseline's own model) and save a resumable checkpoint."""

from __future__ import annotations

import dataclasses
import platform
import time

import torch

from .. import __version__, artifacts, paths
from ..config import ConfigError, ModelConfig, OptimConfig, RunConfig, TaskConfig
from ..envs import make_env
from ..policy import CommTransformer, make_comm
from ..training import FitSpec, FitState, fit
from ..utils.console import ProgressReporter, console, log, use_rich
from ..utils.device import resolve_device
from ..utils.seeding import STREAM_TRAIN, generator, seed_everything
from ._run import Context


def fit_spec(cfg: RunConfig, rollouts: int, lr: float) -> FitSpec:
    o, b = cfg.optim, cfg.budget
    return FitSpec(rollouts=rollouts, batch=b.batch_rollouts, horizon=cfg.horizon, lr=lr,
                   lr_final=min(o.lr_final, lr), grad_clip=o.grad_clip, gamma=o.gamma, detach_state=cfg.task.detach_state,
                   checkpoint_every=b.checkpoint_every, step_per_bucket=o.step_per_bucket,
                   min_steps_per_batch=o.min_steps_per_batch)


# config sections that must match for a checkpoint to be resumed or extended
_SECTIONS = {"task": TaskConfig, "model": ModelConfig, "optim": OptimConfig}


def _defaults(section: str) -> dict:
    """Default values of a config section (a key added after a checkpoint was saved compares as its default)."""
    return {f.name: f.default for f in dataclasses.fields(_SECTIONS[section]) if f.default is not dataclasses.MISSING}


def _check_compatible(saved: dict, current: dict, path) -> None:
    for key in _SECTIONS:
        old, new, dflt = saved.get(key) or {}, current.get(key) or {}, _defaults(key)
        if any(old.get(k, dflt.get(k)) != new.get(k, dflt.get(k)) for k in set(old) | set(new)):
            raise ConfigError(f"{path} was trained with a different `{key}` config; pass overwrite=true to start over "
                              f"or runs_root=... to train elsewhere")


def run(cfg: RunConfig, ctx: Context) -> dict:
    if cfg.baseline.model == "retrained":
        raise ConfigError(f"{cfg.baseline.name} is made by `neurosym retrain`, not `neurosym train`")
    if cfg.baseline.model == "oracle" and cfg.baseline.name != "tf-full":
        log.info("%s runs on the oracle's weights: training the oracle (tf-full)", cfg.baseline.name)
    env = make_env(cfg.task, cfg.horizon)
    # the oracle trains with full soft attention; dist and no-comm train with their own mask
    comm = make_comm("full" if cfg.baseline.model == "oracle" else cfg.baseline.comm, cfg.rules)
    return train_model(cfg, ctx, env, comm, cfg.budget.train_rollouts,
                       lambda: CommTransformer(env.obs_dim, env.action_dim, cfg.task.rounds, cfg.model), "train",
                       cfg.optim.lr)


def train_model(cfg: RunConfig, ctx: Context, env, comm, rollouts: int, init, verb: str, lr: float) -> dict:
    """The one training procedure of `train` and `retrain`: resume or start from ``init()``, fit, save.

    Writes <train_dir>/model.pt every few steps (atomically), history.csv and manifest.json."""
    device = resolve_device(cfg.device)
    seed_everything(cfg.seed)
    spec = fit_spec(cfg, rollouts, lr)
    out = paths.train_dir(cfg)
    ckpt = out / "model.pt"
    run_cfg = ctx.config_dict()
    state = None
    if ckpt.exists() and not cfg.overwrite:
        payload = artifacts.load_checkpoint(ckpt, paths.train_command(cfg))
        _check_compatible(payload["config"], run_cfg, ckpt)
        policy = artifacts.policy_from_payload(payload)
        state = FitState(**payload["fit"])
        if state.step >= spec.steps:
            log.info("already trained: %s (%d optimizer steps); nothing to do (overwrite=true retrains)", ckpt, state.step)
            return {"checkpoint": str(ckpt), "steps": state.step}
        log.info("resuming %s from step %d/%d (%d rollouts done)", ckpt, state.step, spec.steps,
                 state.step * spec.batch)
    else:
        policy = init()
    policy.to(device)

    def save(st: FitState) -> None:
        fit_dict = {"step": st.step, "history": st.history, "optimizer": st.optimizer,
                    "gen_state": st.gen_state, "torch_rng": st.torch_rng}
        payload = artifacts.policy_payload(policy, cfg.model, run_cfg, fit_dict, done=st.step >= spec.steps)
        artifacts.save_checkpoint(ckpt, payload)
        artifacts.write_csv(out / "history.csv", st.history)

    label = f"{verb} {cfg.task.name} {paths.model_name(cfg)} seed{cfg.seed}"
    log.info("%s: %d rollouts, %d per step, T=%d, device %s -> %s", label, spec.rollouts, spec.batch,
             spec.horizon, device, out)
    t0 = time.perf_counter()
    steps_before = state.step if state else 0
    with ProgressReporter(label, use_rich(cfg.progress, ctx.multirun), cfg.budget.log_every) as rep:
        state = fit(policy, env, comm, spec, generator(cfg.seed, STREAM_TRAIN), device, rep, save, state)
    seconds = time.perf_counter() - t0
    rollouts = (state.step - steps_before) * spec.batch
    final = sum(h["loss"] for h in state.history[-5:]) / len(state.history[-5:])
    artifacts.write_json(out / "manifest.json", {
        "command": verb, "version": __version__, "checkpoint": str(ckpt), "steps": state.step,
        "rollouts": min(state.step * spec.batch, spec.rollouts), "final_loss_last5": final,
        "seconds_this_run": seconds, "rollouts_per_second": rollouts / max(seconds, 1e-9),
        "device": str(device), "torch": torch.__version__, "python": platform.python_version(),
        "hydra_dir": ctx.hydra_dir, "config": run_cfg,
    })
    console.print(f"[green]done[/] {label}: loss {final:.3f} (mean of last 5 steps), "
                  f"{rollouts} rollouts in {seconds:.0f} s ({rollouts / max(seconds, 1e-9):.1f} rollouts/s) -> {ckpt}")
    return {"checkpoint": str(ckpt), "steps": state.step, "loss": final}



