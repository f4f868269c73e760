"""`neurosym retrain`: the oracle fine-tuned under the synthesized program (paper section 3.5)."""

from __future__ import annotations

from .. import artifacts, paths
from ..config import ConfigError, RunConfig
from ..envs import make_env
from ._comm import baseline_comm
from ._run import Context
from .train import train_model


def run(cfg: RunConfig, ctx: Context) -> dict:
    if cfg.baseline.model != "retrained":
        raise ConfigError(f"retrain makes baseline=prog-retrained, det-prog-retrained or dt-retrained, "
                          f"not {cfg.baseline.name}")
    comm = baseline_comm(cfg)
    payload = artifacts.load_checkpoint(paths.oracle_checkpoint(cfg), paths.train_command(cfg, oracle=True))
    env = make_env(cfg.task, cfg.horizon)
    # all weights are trained (attention included); random rules draw from the training generator every step
    return train_model(cfg, ctx, env, comm, cfg.budget.retrain_rollouts,
                       lambda: artifacts.policy_from_payload(payload), "retrain", cfg.optim.retrain_lr)
