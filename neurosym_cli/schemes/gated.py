"""rl (paper appendix D): whom to hear as actions, a Bernoulli gate per pair trained by policy gradient beside the
transformer (policy/gated.py); `neurosym rl` trains a grid of them and picks rl1, rl2."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..baselines import ORACLE, Stage
from .families import OwnModel

if TYPE_CHECKING:
    from ..config import RunConfig


@dataclass
class Gated(OwnModel):
    """rl: its own transformer and gate, trained from the oracle (rl.init=oracle) or from scratch."""

    def tag(self, cfg: "RunConfig") -> str:
        """The settings of an rl model: cost weight, reward form, starting point, e.g. c0.1-togo-oracle."""
        return f"c{cfg.rl.cost:g}-{'togo' if cfg.rl.shaped else 'episode'}-{cfg.rl.init}"

    def train_overrides(self, cfg: "RunConfig") -> str:
        return f" rl.cost={cfg.rl.cost:g} rl.shaped={str(cfg.rl.shaped).lower()} rl.init={cfg.rl.init}"

    def requires(self, verb: str) -> tuple[Stage, ...]:
        return (Stage("train", ORACLE),)  # rl starts from the oracle (rl.init=oracle, its default)

    def trains_from_oracle(self, cfg: "RunConfig") -> bool:
        return cfg.rl.init == "oracle"

    def provider(self, cfg: "RunConfig", env: Any = None):
        from ..policy.gated import GatedComm
        from ..tasks.programs import task_of

        return GatedComm(cfg.task.rounds, pair_dim=task_of(cfg, env).pair_dim)  # g_r reads o_ij: the task's Dp
