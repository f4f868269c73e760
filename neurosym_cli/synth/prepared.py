"""Program-independent tensors of one bucket of the synthesis dataset, computed once per search (paper
section 3.4): embeddings, attention logits, projected messages, the later rounds' fixed weights, features and
candidate orders for rule scans, and the memo of each agent's L1 error per picked set."""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor

from ..tasks.features import FeatureMap
from ..policy.transformer import CommTransformer, selected_attention
from .dataset import DataBucket

MEMO = 4  # memo slots per agent
# the projected message of every pair is cached when there are at most this many pairs (S N N; 32M is ~2 GB);
# beyond it the scorer recomputes the K picked messages per agent from the values and pair observations
MESSAGES_MAX_PAIRS = 32_000_000


class Prepared:
    """Program-independent tensors of one bucket."""

    def __init__(self, policy: CommTransformer, fmap: FeatureMap, b: DataBucket, round_idx: int,
                 device: torch.device, memo: bool):
        self.s, self.n = b.states, b.n_agents
        self.agent, self.rel, self.target = b.agent.to(device), b.rel.to(device), b.target.to(device)
        self.feats = fmap.view(self.agent, self.rel)
        h = torch.relu(policy.embed(self.agent))  # (S, N, D)
        # per round (S, N, N); in chunks of ~1M pairs, since the keys are (S, N, N, D) before the reduction
        ch = max(1, 1_000_000 // (self.n * self.n))
        self.logits = [torch.cat([layer.logits(h[c:c + ch], self.rel[c:c + ch]) for c in range(0, self.s, ch)])
                       for layer in policy.rounds]
        x = h
        others = ~torch.eye(self.n, dtype=torch.bool, device=device).expand(self.s, -1, -1)
        for q in range(round_idx):  # rounds before the synthesized one use full soft attention
            x, _ = policy.rounds[q].aggregate(x, self.logits[q], others, self.rel)
        layer = policy.rounds[round_idx]
        # W_o is linear, so W_o sum_j a_ij m_j->i + b_o = sum_j a_ij (W_o m_j->i) + b_o (the a_ij sum to 1 or 0):
        # cache x_i + b_o and the projected messages W_o m_j->i instead of projecting every row per proposal
        self.base = (x + layer.out.bias).reshape(-1, x.shape[-1])  # (S N, D)
        self.values = layer.value(x)  # (S, N, D)
        self.others = others
        # the projected message of every pair, when it fits (MESSAGES_MAX_PAIRS): scoring then gathers K
        # messages per agent instead of recomputing them
        self.messages: Tensor | None = None
        if self.s * self.n * self.n <= MESSAGES_MAX_PAIRS:
            self.messages = torch.cat([
                F.linear(layer.message(self.values[c:c + ch, None, :, :],
                                       self.rel[c:c + ch].transpose(1, 2)),  # [i, j] = m_j->i from o_ji
                         layer.out.weight)
                for c in range(0, self.s, ch)]).reshape(-1, x.shape[-1])  # (S N N, D): [s, i, j] = j -> i
        self.logits_flat = self.logits[round_idx].reshape(-1)  # (S N N,)
        # later rounds attend softly over everybody with logits from the original state, so their weights A and
        # the message part C_i = sum_j a_ij ReLU(W_m o_ji) do not depend on the program: a later round is then
        # one (N, N) x (N, D) product per state plus its post-attention block (appendix A, round r < last)
        self.later: list[tuple[Tensor, Tensor]] = []
        for q in range(round_idx + 1, policy.n_rounds):
            lay = policy.rounds[q]
            a = selected_attention(self.logits[q], others, dense=True)  # (S, N, N)
            c = torch.cat([(a[c:c + ch, :, :, None] * torch.relu(lay.msg_edge(self.rel[c:c + ch].transpose(1, 2))))
                           .sum(2) for c in range(0, self.s, ch)])  # (S, N, D)
            self.later.append((a, c))
        self.target_flat = self.target.reshape(self.s * self.n, -1)  # (S N, A)
        self.agent_flat = self.agent.reshape(self.s * self.n, -1)  # (S N, Ds): what a task's target may read
        self.uniforms: dict[tuple[int, int], Tensor] = {}
        # memo of each agent's L1 error per set of picked agents: a proposal often gives an agent a set it had
        # under an earlier program (a rule moved back, another rule changed). A set is named by the sum of random
        # 40-bit codes of its members (+1, so that no set is 0 = empty slot); MEMO slots per agent, direct-mapped.
        # Only the last round has per-agent errors to remember (an earlier round's program changes every agent).
        self.codes = torch.randint(1, 2**40, (self.n,), generator=torch.Generator().manual_seed(self.n),
                                   dtype=torch.int64).to(device)
        rows = self.s * self.n if memo else 0
        self.memo_key = torch.zeros(rows, MEMO, dtype=torch.int64, device=device)
        self.memo_l1 = torch.zeros(rows, MEMO, device=device)
        # picks are agent indices, stored small: int8 up to 127 agents, int16 beyond
        self.pick_dtype = torch.int8 if self.n <= 127 else torch.int16
        self.todo: tuple[Tensor, Tensor, Tensor, Tensor] | None = None  # scratch of the compiled path
        self.scan: tuple[list[str], list[str], np.ndarray, np.ndarray] | None = None
        self.orders: dict[tuple, np.ndarray] = {}

    def scan_inputs(self) -> tuple[list[str], list[str], np.ndarray, np.ndarray]:
        """(pair names, agent names, pair features (P, S N N), agent features (A, S N)) for kernels.scan_picks;
        the stacked tensors replace the feature view's own copies, so memory is not doubled."""
        if self.scan is None:
            self.scan = self.feats.stacked()
        return self.scan

    def order(self, key: tuple, values: Tensor | None = None) -> np.ndarray:
        """(S N, N) candidates (pick_dtype) of every agent, best first, ties by lower index (torch's max): by a pair
        feature's value (key ("score", name, descending)) or by the given uniforms (key ("random", position, r))."""
        if key not in self.orders:
            if key[0] == "score":
                pair, _, fp, _ = self.scan_inputs()
                v = torch.from_numpy(fp[pair.index(key[1])])
                values = -v if key[2] else v
            else:
                assert values is not None
                values = -values
            idx = torch.sort(values.reshape(-1, self.n), stable=True).indices
            self.orders[key] = idx.to(self.pick_dtype).numpy()
        return self.orders[key]

    def set_key(self, picks: Tensor, valid: Tensor) -> Tensor:
        """(M, K) picks and valid -> (M,) int64 name of each row's set of picked agents."""
        return 1 + torch.where(valid, self.codes[picks.clamp(min=0)], 0).sum(-1)

    def recall(self, rows: Tensor, key: Tensor) -> tuple[Tensor, Tensor]:
        """(hit (M,) bool, L1 (M,) where hit) for rows (M,) with set names key (M,)."""
        match = self.memo_key.index_select(0, rows) == key[:, None]  # (M, MEMO)
        vals = (self.memo_l1.index_select(0, rows) * match).sum(-1)
        return match.any(-1), vals

    def remember(self, rows: Tensor, key: Tensor, l1: Tensor) -> None:
        slot = rows * MEMO + key % MEMO
        self.memo_key.view(-1)[slot] = key
        self.memo_l1.view(-1)[slot] = l1
