"""`neurosym retrain`: the oracle fine-tuned under the synthesized program (paper section 3.5)."""

from __future__ import annotations

from .. import artifacts, paths
from ..config import ConfigError, RunConfig
from ..envs import make_env
from ..policy.comm import ProgramComm
from ..utils.io import load_program
from ._run import Context
from .train import train_model


def run(cfg: RunConfig, ctx: Context) -> dict:
    if cfg.baseline.model != "retrained":
        raise ConfigError(f"retrain makes baseline=prog-retrained or det-prog-retrained, not {cfg.baseline.name}")
    program = load_program(paths.program_file(cfg), paths.synth_command(cfg))
    if program.n_rounds != cfg.task.rounds:
        raise ConfigError(f"the program has {program.n_rounds} round(s), the task {cfg.task.rounds}")
    payload = artifacts.load_checkpoint(paths.oracle_checkpoint(cfg), paths.train_command(cfg, oracle=True))
    env = make_env(cfg.task, cfg.horizon)
    # all weights are trained (attention included); random rules draw from the training generator every step
    comm = ProgramComm(program, cfg.task.kind, cfg.features)
    return train_model(cfg, ctx, env, comm, cfg.budget.retrain_rollouts,
                       lambda: artifacts.policy_from_payload(payload), "retrain")
