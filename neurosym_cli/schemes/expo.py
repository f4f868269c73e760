"""expo: ExpoComm's exponential graph (Li et al., ICLR 2025, "Exponential Topology-enabled Scalable Communication
in Multi-agent Reinforcement Learning"), its one-peer mode, as a fixed rule under the shared transformer."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from .families import OwnRule

if TYPE_CHECKING:
    from torch import Tensor

    from ..policy.comm import CommContext


@dataclass
class Expo(OwnRule):
    """expo: its own transformer; at step t agent i hears agent (i + 2^k) mod N, k = t mod ceil(log2 N), so every
    agent hears exactly one and is heard by exactly one, and in ceil(log2 N) steps a message can reach everybody
    (ExpoComm section 4.1, one-peer exponential graph; docs/fidelity.md, 'ExpoComm')."""

    def picks(self, ctx: "CommContext", round: int) -> "Tensor":
        import torch

        b, n = ctx.obs.agent.shape[:2]
        device = ctx.obs.agent.device
        if n < 2:  # nobody else to hear
            return torch.zeros(b, n, 0, dtype=torch.long, device=device)
        period = (n - 1).bit_length()  # ceil(log2 N) for N >= 2: 2^k < N, so nobody hears itself
        peer = (torch.arange(n, device=device) + (1 << (ctx.step % period))) % n  # every round of step t alike
        return peer.view(1, n, 1).expand(b, n, 1).contiguous()  # (B, N, 1): the sparse path
