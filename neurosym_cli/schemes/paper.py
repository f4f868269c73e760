"""The paper's fixed-rule baselines (section 4): tf-full, hard-attn, dist, no-comm. Their providers live in
policy/comm.py beside the others the paper's method uses."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .families import OnOracle, OwnModel

if TYPE_CHECKING:
    from ..config import RunConfig


@dataclass
class Full(OnOracle):
    """tf-full: the oracle, soft attention over every other agent (paper section 3.1)."""

    soft_attention = True

    def provider(self, cfg: "RunConfig", env: Any = None):
        from ..policy.comm import FullComm

        return FullComm()


@dataclass
class TopK(OnOracle):
    """hard-attn: the oracle, each agent hears its k = rules largest attention logits."""

    def label(self, cfg: "RunConfig") -> str:
        return f"{self.name}-k{cfg.rules}"

    def provider(self, cfg: "RunConfig", env: Any = None):
        from ..policy.comm import TopKComm

        return TopKComm(cfg.rules)


@dataclass
class Nearest(OwnModel):
    """dist: its own transformer, each agent hearing its k = rules nearest agents (noise-free distances)."""

    def tag(self, cfg: "RunConfig") -> str:
        return f"k{cfg.rules}"

    def train_overrides(self, cfg: "RunConfig") -> str:
        return f" rules={cfg.rules}"

    def provider(self, cfg: "RunConfig", env: Any = None):
        from ..policy.comm import NearestComm

        return NearestComm(cfg.rules)


@dataclass
class Silent(OwnModel):
    """no-comm: its own transformer, nobody hearing anybody (the reference point)."""

    def provider(self, cfg: "RunConfig", env: Any = None):
        from ..policy.comm import NoComm

        return NoComm()
