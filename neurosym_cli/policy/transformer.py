"""The transformer policy of paper section 3.1 (and appendix A for several rounds).

Per round r, with h_i = ReLU(W_s s_i) the state embedding:
    query      q_i    = W_q h_i / sqrt(d)                     (pi^Q: depends on s_i only)
    key        k_ij   = ReLU(W_k o_ij)                        (pi^K(s_i, o_ij): edge-only key, decentralised)
    logits     l_ij   = <q_i, k_ij>                           (eq. tf_softmax)
    message    m_j->i = W_v x_j + ReLU(W_m o_ji)              (pi^M(s_j, o_ji): sender's state, sender's view)
    attention  a_ij   = softmax_j over the agents that i hears (mask from a communication provider); a row with
                        nobody heard aggregates nothing. This is the paper's alpha^P = alpha / Z (section 3.3).
    output     y_i    = LN(z_i + FFN(z_i)),  z_i = LN(x_i + W_o sum_j a_ij m_j->i)   (post-LN, as the reference)
Round 1 has x = h; round 2 has x = y of round 1 (the internal state of appendix A) while its keys and queries
still come from the original state s_i. The action is a linear read-out of the last y.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import torch
from torch import Tensor, nn

from ..config import ModelConfig
from ..envs.base import Observation

Selector = Callable[[Tensor, int], Tensor]
"""(logits (B, N, N), round) -> mask (B, N, N) bool, True where agent i hears agent j."""

NEG = -1e9  # finite, so rows where nobody is heard give zeros instead of NaN gradients


@dataclass
class PolicyOutput:
    action: Tensor  # (B, N, A)
    attn: list[Tensor]  # per round (B, N, N): weights a_ij actually used (zero outside the mask)
    masks: list[Tensor]  # per round (B, N, N) bool: who heard whom


class CommRound(nn.Module):
    """One round of communication: attention logits, masked aggregation, post-attention block."""

    def __init__(self, width: int, ffn: int, dropout: float):
        super().__init__()
        d = width
        self.scale = 1.0 / math.sqrt(d)
        self.query = nn.Linear(d, d)
        self.key_edge = nn.Linear(2, d)
        self.value = nn.Linear(d, d)
        self.msg_edge = nn.Linear(2, d)
        self.out = nn.Linear(d, d)
        self.ffn1 = nn.Linear(d, ffn)
        self.ffn2 = nn.Linear(ffn, d)
        self.norm1 = nn.LayerNorm(d)
        self.norm2 = nn.LayerNorm(d)
        self.drop = nn.Dropout(dropout)

    def logits(self, h: Tensor, rel: Tensor) -> Tensor:
        """h: (B, N, D) state embedding, rel: (B, N, N, 2) -> (B, N, N) attention logits l_ij."""
        q = self.query(h) * self.scale  # (B, N, D)
        k = torch.relu(self.key_edge(rel))  # (B, N, N, D): k_ij from o_ij
        # multiply-and-sum beats a batched mat-vec here (many (N, D) x (D,) products are 2x slower on CPU)
        return (k * q.unsqueeze(2)).sum(-1)

    def aggregate(self, x: Tensor, logits: Tensor, mask: Tensor, rel: Tensor) -> tuple[Tensor, Tensor]:
        """x: (B, N, D) round input; returns the round output (B, N, D) and the weights (B, N, N)."""
        attn = torch.softmax(logits.masked_fill(~mask, NEG), -1) * mask  # (B, N, N), rows sum to 1 or 0
        w = self.drop(attn)
        # the message j -> i uses the sender's view o_ji: transpose the 2-d input, not the D-wide output
        msg_edge = torch.relu(self.msg_edge(rel.transpose(1, 2)))  # (B, N, N, D): [i, j] from o_ji
        agg = torch.bmm(w, self.value(x)) + (w.unsqueeze(-1) * msg_edge).sum(2)  # (B, N, D)
        z = self.norm1(x + self.drop(self.out(agg)))
        y = self.norm2(z + self.drop(self.ffn2(self.drop(torch.relu(self.ffn1(z))))))
        return y, attn


class CommTransformer(nn.Module):
    """Shared by every agent; all computation is batched over (B, N)."""

    def __init__(self, obs_dim: int, action_dim: int, rounds: int, cfg: ModelConfig):
        super().__init__()
        self.obs_dim, self.action_dim, self.n_rounds = obs_dim, action_dim, rounds
        self.embed = nn.Linear(obs_dim, cfg.width)
        self.rounds = nn.ModuleList(CommRound(cfg.width, cfg.ffn, cfg.dropout) for _ in range(rounds))
        self.head = nn.Linear(cfg.width, action_dim)

    def forward(self, obs: Observation, select: Selector) -> PolicyOutput:
        h = torch.relu(self.embed(obs.agent))  # (B, N, D)
        x = h
        attn, masks = [], []
        for r, layer in enumerate(self.rounds):
            logits = layer.logits(h, obs.rel)
            mask = select(logits.detach(), r)
            x, a = layer.aggregate(x, logits, mask, obs.rel)
            attn.append(a)
            masks.append(mask)
        return PolicyOutput(self.head(x), attn, masks)
