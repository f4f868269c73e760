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

Two paths compute the same round. The dense one scores all N^2 pairs and lets the provider choose from the
logits (tf-full, hard-attn). The sparse one serves providers that know whom each agent hears before any logit
(no-comm, dist, prog): it computes keys, logits and messages only for the B N K picked pairs, which makes
training under a degree-K provider N/K times lighter in its (B, N, N, D) work (docs/performance.md). For a large
team the observation comes as a pair source (tasks/pairs.py ``Offsets``): the sparse round then computes o_ij and
o_ji at the picked pairs only and returns whom each agent heard as picks (``Heard``), so nothing of size
(B, N, N) is built and the gradients touch O(B N K) pairs (docs/performance.md, section 15).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import torch
from torch import Tensor, nn

from ..config import ModelConfig
from ..dsl.interpret import dedup_valid, picks_to_mask
from ..tasks.base import Observation
from ..tasks.pairs import Offsets
from ..utils.ops import softmax_last
from . import edge_kernels

Selector = Callable[[Tensor, int], Tensor]
"""(logits (B, N, N), round) -> mask (B, N, N) bool, True where agent i hears agent j."""

PickSource = Callable[[int], "Tensor | None"]
"""round -> (B, N, K) long: the agents each agent hears (-1 = nobody, repeats allowed), or None when the
provider needs the logits to decide (dense path)."""

NEG = -1e9  # finite, so rows where nobody is heard give zeros instead of NaN gradients


def selected_attention(logits: Tensor, keep: Tensor, dense: bool = False) -> Tensor:
    """The paper's alpha^P_ij = alpha_ij / Z_i (section 3.3): softmax of i's logits over the agents it hears, zero
    elsewhere; a row where nobody is heard is all zero. logits, keep: (..., M) over M candidates, all N agents
    (dense) or the K picked ones. Dense rows keep torch's softmax kernel: the written-out one (utils/ops.py) is
    faster on short rows but rounds differently, and every trained checkpoint was made with torch's."""
    x = logits.masked_fill(~keep, NEG)
    return (torch.softmax(x, -1) if dense else softmax_last(x)) * keep


@dataclass
class Heard:
    """Whom each agent heard in one round of the sparse path of a large team, kept as picks: the dense mask and
    weights (B, N, N) are built only when asked for (a picture of a small team)."""

    picks: Tensor  # (B, N, K) long, -1 = nobody
    valid: Tensor  # (B, N, K) bool: the pick counts (not -1, not a repeat of an earlier rule's pick)
    weights: Tensor  # (B, N, K) attention weight of each pick (0 where not valid)

    @property
    def n(self) -> int:
        return self.picks.shape[1]

    def mask(self) -> Tensor:
        """(B, N, N) bool: i hears j."""
        return picks_to_mask(torch.where(self.valid, self.picks, -1), self.n)

    def attn(self) -> Tensor:
        """(B, N, N) the weights a_ij (zero outside the mask)."""
        b, n, _ = self.picks.shape
        return torch.zeros(b, n, n, device=self.picks.device).scatter_add(-1, self.picks.clamp(min=0), self.weights)

    def degrees(self) -> tuple[Tensor, Tensor]:
        """(B, N) in-degree (agents heard) and (B, N) out-degree (agents that hear it), float counts: the row and
        column sums of ``mask`` without building it."""
        b, n, k = self.picks.shape
        v = self.valid.to(torch.float32)
        deg_out = torch.zeros(b, n, device=v.device).scatter_add(-1, self.picks.clamp(min=0).reshape(b, n * k),
                                                                 v.reshape(b, n * k))
        return v.sum(-1), deg_out


@dataclass
class PolicyOutput:
    action: Tensor  # (B, N, A)
    heard: list  # per round: (weights (B, N, N), mask (B, N, N) bool) of the dense path, or a Heard (sparse)

    @property
    def attn(self) -> list[Tensor]:
        """Per round (B, N, N): weights a_ij actually used (zero outside the mask)."""
        return [h.attn() if isinstance(h, Heard) else h[0] for h in self.heard]

    @property
    def masks(self) -> list[Tensor]:
        """Per round (B, N, N) bool: who heard whom."""
        return [h.mask() if isinstance(h, Heard) else h[1] for h in self.heard]


class CommRound(nn.Module):
    """One round of communication: attention logits, masked aggregation, post-attention block."""

    def __init__(self, width: int, ffn: int, dropout: float, pair_dim: int = 2):
        super().__init__()
        d = width
        self.scale = 1.0 / math.sqrt(d)
        self.query = nn.Linear(d, d)
        self.key_edge = nn.Linear(pair_dim, d)  # Dp: the task's pair observation width
        self.value = nn.Linear(d, d)
        self.msg_edge = nn.Linear(pair_dim, d)
        self.out = nn.Linear(d, d)
        self.ffn1 = nn.Linear(d, ffn)
        self.ffn2 = nn.Linear(ffn, d)
        self.norm1 = nn.LayerNorm(d)
        self.norm2 = nn.LayerNorm(d)
        self.drop = nn.Dropout(dropout)

    def logits(self, h: Tensor, rel: Tensor) -> Tensor:
        """h: (B, N, D) state embedding, rel: (B, N, N, Dp) -> (B, N, N) attention logits l_ij."""
        q = self.query(h) * self.scale  # (B, N, D)
        if edge_kernels.serves(rel):  # compile=fused: one pass over the pairs, nothing (B, N, N, D) stored
            return edge_kernels.key_logits(q, rel, self.key_edge)
        k = torch.relu(self.key_edge(rel))  # (B, N, N, D): k_ij from o_ij
        # multiply-and-sum beats a batched mat-vec here (many (N, D) x (D,) products are 2x slower on CPU)
        return (k * q.unsqueeze(2)).sum(-1)

    def message(self, v_j: Tensor, o_ji: Tensor) -> Tensor:
        """pi^M(s_j, o_ji) = W_v x_j + ReLU(W_m o_ji): v_j (..., D) the sender's value, o_ji (..., Dp) its view of
        the receiver -> (..., D)."""
        return v_j + torch.relu(self.msg_edge(o_ji))

    def attend(self, logits: Tensor, keep: Tensor, messages: Tensor) -> tuple[Tensor, Tensor]:
        """Attention over selected agents: logits, keep (..., K) of the candidate pairs, messages (..., K, D) ->
        the aggregate sum_k a_k m_k (..., D) and the weights a (..., K). Messages may come projected by W_o
        (the scorer's cache): the sum is linear in them."""
        attn = selected_attention(logits, keep)
        return (self.drop(attn).unsqueeze(-1) * messages).sum(-2), attn

    def aggregate(self, x: Tensor, logits: Tensor, mask: Tensor, rel: Tensor) -> tuple[Tensor, Tensor]:
        """Dense path: x (B, N, D) round input, logits (B, N, N), mask (B, N, N) -> round output (B, N, D), weights
        (B, N, N). The same sum as ``attend`` over all N agents, split by linearity into sum_j a_ij W_v x_j (one
        batched product) plus sum_j a_ij ReLU(W_m o_ji), so no (B, N, N, D) value tensor is built."""
        attn = selected_attention(logits, mask, dense=True)  # (B, N, N), rows sum to 1 or 0
        w = self.drop(attn)
        if edge_kernels.serves(rel):  # compile=fused
            return self._post(x, torch.bmm(w, self.value(x)) + edge_kernels.edge_messages(w, rel, self.msg_edge)), attn
        # the message j -> i uses the sender's view o_ji: transpose the 2-d input, not the D-wide output
        msg_edge = torch.relu(self.msg_edge(rel.transpose(1, 2)))  # (B, N, N, D): [i, j] from o_ji
        agg = torch.bmm(w, self.value(x)) + (w.unsqueeze(-1) * msg_edge).sum(2)  # (B, N, D)
        return self._post(x, agg), attn

    def aggregate_picks(self, x: Tensor, h: Tensor, rel: "Tensor | Offsets", picks: Tensor
                        ) -> tuple[Tensor, "tuple[Tensor, Tensor] | Heard"]:
        """Sparse path: the round with its mask given as picks (B, N, K) long (-1 = nobody, repeats count once):
        the same function as ``aggregate(x, logits(h, rel), mask)`` computed on the picked pairs only. Returns
        the round output (B, N, D) and whom each agent heard: (weights (B, N, N), mask (B, N, N) bool) for a dense
        ``rel``, a ``Heard`` for a pair source (nothing of size N^2 built)."""
        b, n, k = picks.shape
        valid = dedup_valid(picks) if k else torch.zeros_like(picks, dtype=torch.bool)  # (B, N, K)
        if k == 0:  # nobody is heard: the aggregate is zero and no logit or message is needed
            y, attn_k = self._post(x, torch.zeros_like(x)), torch.zeros(b, n, 0, device=x.device)
        else:
            y, attn_k = self.picked_round(x, h, rel, picks, valid)
        if isinstance(rel, Offsets):
            return y, Heard(picks, valid, attn_k)
        mask = picks_to_mask(torch.where(valid, picks, -1), n)
        if k == 0:
            return y, (torch.zeros(b, n, n, device=x.device), mask)
        attn = torch.zeros(b, n, n, device=x.device).scatter_add(-1, picks.clamp(min=0), attn_k)  # repeats: 0
        return y, (attn, mask)

    def picked_round(self, x: Tensor, h: Tensor, rel: "Tensor | Offsets", picks: Tensor, valid: Tensor
                     ) -> tuple[Tensor, Tensor]:
        """The sparse round's output (B, N, D) and weights over the picks (B, N, K), for K >= 1 picks (B, N, K) and
        which of them count, ``valid`` (B, N, K) bool (dedup_valid). What policy export traces (no mask built).
        ``rel``: the dense o_ij (B, N, N, Dp), or a pair source that computes the 2 B N K views read here."""
        b, n, k = picks.shape
        idx = picks.clamp(min=0)
        # the logits before the messages: the order the graph is built in is the order autograd sums gradients
        # into the state, and every checkpoint was trained with this one
        q = self.query(h) * self.scale  # (B, N, D)
        if isinstance(rel, Offsets):
            recv = torch.arange(n, device=idx.device).view(1, n, 1).expand(b, n, k)
            o_ij = rel.at(recv, idx)  # (B, N, K, 2): receiver i's view of j, computed here
        else:
            p = rel.shape[-1]  # Dp
            o_ij = rel.gather(2, idx.unsqueeze(-1).expand(b, n, k, p))  # (B, N, K, Dp): receiver i's view of j
        logits = self.picked_logits(q, o_ij)  # (B, N, K)
        if isinstance(rel, Offsets):
            o_ji = rel.at(idx, recv)  # (B, N, K, 2): the sender's view of the receiver
        else:
            # the message j -> i uses the sender's view o_ji = rel[j, i]: flat index j N + i of the (N N) pairs
            send = (idx * n + torch.arange(n, device=idx.device).view(1, n, 1)).reshape(b, n * k, 1)
            o_ji = rel.reshape(b, n * n, p).gather(1, send.expand(-1, -1, p)).view(b, n, k, p)
        v = self.value(x)  # (B, N, D)
        v_j = v.gather(1, idx.reshape(b, n * k, 1).expand(-1, -1, v.shape[-1])).view(b, n, k, -1)  # (B, N, K, D)
        return self.combine(x, logits, self.message(v_j, o_ji), valid)

    def picked_logits(self, q: Tensor, o_ij: Tensor) -> Tensor:
        """q (..., D) the receiver's scaled query, o_ij (..., K, Dp) its views of the K asked -> logits (..., K)."""
        return (torch.relu(self.key_edge(o_ij)) * q.unsqueeze(-2)).sum(-1)

    def combine(self, x: Tensor, logits: Tensor, messages: Tensor, valid: Tensor) -> tuple[Tensor, Tensor]:
        """Round input x (..., D), logits (..., K), messages (..., K, D), valid (..., K) -> output (..., D), weights."""
        agg, attn_k = self.attend(logits, valid, messages)  # (..., D), (..., K)
        return self._post(x, agg), attn_k

    def receive(self, x: Tensor, h: Tensor, o_ij: Tensor, messages: Tensor, valid: Tensor) -> tuple[Tensor, Tensor]:
        """What receiver i does with the messages of the K agents it asked: x (..., D) its round input, h (..., D)
        its state embedding, o_ij (..., K, Dp) its views of them, messages (..., K, D) theirs (``message``), valid
        (..., K) bool which slots count -> its round output (..., D) and the weights (..., K). The same code as the
        batched team's round (picked_logits, combine), for one agent on its own (policy export)."""
        return self.combine(x, self.picked_logits(self.query(h) * self.scale, o_ij), messages, valid)

    def _post(self, x: Tensor, agg: Tensor) -> Tensor:
        """(B, N, D) round input and aggregate -> round output y = finish(x + W_o agg + b_o)."""
        return self.finish(x + self.drop(self.out(agg)))

    def finish(self, z: Tensor) -> Tensor:
        """(..., D) residual sum x + W_o agg + b_o -> round output: post-LN block LN(z' + FFN(z')), z' = LN(z)."""
        z = self.norm1(z)
        return self.norm2(z + self.drop(self.ffn2(self.drop(torch.relu(self.ffn1(z))))))


class CommTransformer(nn.Module):
    """Shared by every agent; all computation is batched over (B, N). Its widths come from the task: agent input
    Ds = ``obs_dim``, pair input Dp = ``pair_dim``, action A = ``action_dim``."""

    @classmethod
    def for_task(cls, task, cfg: ModelConfig) -> "CommTransformer":
        """The transformer sized by a task's declared widths and rounds."""
        return cls(task.obs_dim, task.action_dim, task.rounds, cfg, task.pair_dim)

    def __init__(self, obs_dim: int, action_dim: int, rounds: int, cfg: ModelConfig, pair_dim: int = 2):
        super().__init__()
        self.obs_dim, self.action_dim, self.n_rounds, self.pair_dim = obs_dim, action_dim, rounds, pair_dim
        self.embed = nn.Linear(obs_dim, cfg.width)
        self.rounds = nn.ModuleList(CommRound(cfg.width, cfg.ffn, cfg.dropout, pair_dim) for _ in range(rounds))
        self.head = nn.Linear(cfg.width, action_dim)

    @property
    def message_dim(self) -> int:
        """D, the floats of one message m_j->i (the value width, model.width): what a heard agent sends per round."""
        return self.embed.out_features

    def forward(self, obs: Observation, select: Selector, picks: PickSource | None = None) -> PolicyOutput:
        """``picks``, when given and not None for a round, replaces ``select`` there (sparse path)."""
        h = torch.relu(self.embed(obs.agent))  # (B, N, D)
        x = h
        heard = []
        for r, layer in enumerate(self.rounds):
            pk = picks(r) if picks is not None else None
            if pk is None:
                logits = layer.logits(h, obs.rel)
                mask = select(logits.detach(), r)
                x, a = layer.aggregate(x, logits, mask, obs.rel)
                heard.append((a, mask))
            else:
                x, got = layer.aggregate_picks(x, h, obs.pairs if obs.pairs is not None else obs.rel, pk)
                heard.append(got)
        return PolicyOutput(self.head(x), heard)
