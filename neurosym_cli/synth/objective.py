"""The synthesis objective of paper section 3.4, scored fast.

    J(P) = mean over states of [ sum_i ||a_i - a_i^P||_1 ] + lam * mean over states of [ max_i deg(i; c^P) ]

a is the oracle's action, a^P the action of the same transformer when each agent hears only the agents P picks
(soft attention renormalised over them, section 3.3); deg = in + out. ``objective=hinge`` uses the reference's
lam * (relu(max in - K) + relu(max out - K)) instead.

The scorer caches everything that does not depend on the program (state embeddings, attention logits, value
vectors, features, and the uniforms of random rules: common random numbers), evaluates only the rules a
proposal changed (each rule's picks are cached), and recomputes the action only for the agents whose set of
picked agents changed, aggregating over the <= K picked agents instead of all N. ``full_score`` is the
reference-style scorer (a full forward pass of the transformer over D) used to check it and to benchmark it.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import torch
from torch import Tensor

from ..dsl.ast import Program, RandomRule, Rule
from ..dsl.interpret import picks_to_mask, rule_picks
from ..envs.base import MultiAgentEnv, Observation
from ..envs.features import PairFeatures
from ..policy.transformer import NEG, CommTransformer
from .dataset import DataBucket


@dataclass(frozen=True)
class Score:
    total: float
    l1: float  # mean over states of sum_i ||a_i - a^P_i||_1
    degree: float  # mean over states of the degree term, before lam


class _Uniforms:
    """A UniformSource that returns fixed draws (common random numbers across proposals)."""

    def __init__(self, u: Tensor):
        self.u = u

    def rand(self, batch: int, *shape: int) -> Tensor:
        return self.u


def dedup_valid(picks: Tensor) -> Tensor:
    """picks (..., K) with -1 for none -> (..., K) bool: valid and not a repeat of an earlier rule's pick."""
    k = picks.shape[-1]
    same = picks.unsqueeze(-1) == picks.unsqueeze(-2)  # (..., K, K): [a, b] pick a equals pick b
    earlier = torch.ones(k, k, dtype=torch.bool, device=picks.device).tril(-1)  # b < a
    return (picks >= 0) & ~(same & earlier).any(-1)


def degree_term(picks: Tensor, valid: Tensor, n: int, objective: str, cap: int) -> Tensor:
    """picks, valid: (S, N, K) -> (S,) the per-state degree term."""
    s = picks.shape[0]
    deg_in = valid.sum(-1)  # (S, N)
    idx = torch.where(valid, picks, n).flatten(1)  # (S, N K); invalid picks land in column n
    deg_out = torch.zeros(s, n + 1, dtype=deg_in.dtype, device=picks.device).scatter_add_(1, idx, torch.ones_like(idx))
    deg_out = deg_out[:, :n]
    if objective == "hinge":
        return (torch.relu(deg_in.amax(-1) - cap) + torch.relu(deg_out.amax(-1) - cap)).float()
    return (deg_in + deg_out).amax(-1).float()


class _Prepared:
    """Program-independent tensors of one bucket."""

    def __init__(self, policy: CommTransformer, kind: str, b: DataBucket, round_idx: int, version: str,
                 device: torch.device):
        self.s, self.n = b.states, b.n_agents
        self.agent, self.rel, self.target = b.agent.to(device), b.rel.to(device), b.target.to(device)
        self.feats = PairFeatures(kind, self.agent, self.rel, version)
        h = torch.relu(policy.embed(self.agent))  # (S, N, D)
        # per round (S, N, N); in chunks of states, since the keys are (S, N, N, D) before the reduction
        self.logits = [torch.cat([layer.logits(h[c:c + 2048], self.rel[c:c + 2048]) for c in range(0, self.s, 2048)])
                       for layer in policy.rounds]
        x = h
        others = ~torch.eye(self.n, dtype=torch.bool, device=device).expand(self.s, -1, -1)
        for q in range(round_idx):  # rounds before the synthesized one use full soft attention
            x, _ = policy.rounds[q].aggregate(x, self.logits[q], others, self.rel)
        self.x_in = x  # (S, N, D) input of the synthesized round
        layer = policy.rounds[round_idx]
        self.values = layer.value(x)  # (S, N, D)
        self.others = others
        # the full message m_j->i = W_v x_j + ReLU(W_m o_ji) of every pair, when it fits (<= 8M pairs, ~0.5 GB):
        # scoring then gathers K messages per agent instead of recomputing them
        self.messages: Tensor | None = None
        if self.s * self.n * self.n <= 8_000_000:
            self.messages = torch.cat([
                self.values[c:c + 2048, None, :, :]
                + torch.relu(layer.msg_edge(self.rel[c:c + 2048].transpose(1, 2)))  # [i, j] from o_ji
                for c in range(0, self.s, 2048)])  # (S, N, N, D): [s, i, j] = message j -> i
        self.uniforms: list[Tensor] = []


class CachedScorer:
    """Incremental scorer of programs for one communication round (paper appendix A: one program per round)."""

    def __init__(self, policy: CommTransformer, env: MultiAgentEnv, kind: str, buckets: list[DataBucket],
                 round_idx: int, version: str, lam: float, objective: str, cap: int, samples: int,
                 gen: torch.Generator, device: torch.device, cache_size: int = 256):
        self.policy = policy.eval()
        self.env, self.round, self.lam, self.objective, self.cap = env, round_idx, lam, objective, cap
        self.samples, self.gen, self.device = samples, gen, device
        self.last_round = round_idx == policy.n_rounds - 1
        with torch.no_grad():
            self.data = [_Prepared(policy, kind, b, round_idx, version, device) for b in buckets]
        self.total_states = sum(d.s for d in self.data)
        self.rule_cache: OrderedDict[Rule, list[Tensor]] = OrderedDict()
        self.cache_size = cache_size
        self.current: tuple | None = None  # (rules, per-bucket picks (R, S, N, K), per-bucket l1 rows (R, S, N))
        self.pending: tuple | None = None
        self.rows_recomputed = 0

    # ------------------------------------------------------------------------------------------ picks
    def _uniforms(self, d: _Prepared) -> list[Tensor]:
        if not d.uniforms:
            d.uniforms = [torch.rand(d.s, d.n, d.n, generator=self.gen).to(self.device) for _ in range(self.samples)]
        return d.uniforms

    def picks_of(self, rule: Rule) -> list[Tensor]:
        """Per bucket (R, S, N) int8 picks of one rule (R = samples for random rules, else 1); cached."""
        if rule in self.rule_cache:
            self.rule_cache.move_to_end(rule)
            return self.rule_cache[rule]
        out = []
        for d in self.data:
            if isinstance(rule, RandomRule):
                ps = [rule_picks(rule, d.feats, _Uniforms(u)) for u in self._uniforms(d)]
            else:
                ps = [rule_picks(rule, d.feats, None)]
            out.append(torch.stack(ps).to(torch.int8))
        self.rule_cache[rule] = out
        if len(self.rule_cache) > self.cache_size:
            self.rule_cache.popitem(last=False)
        return out

    def _program_picks(self, rules: tuple[Rule, ...]) -> list[Tensor]:
        """Per bucket (R, S, N, K) long, R = samples (deterministic rules broadcast)."""
        per_rule = [self.picks_of(r) for r in rules]
        out = []
        for bi in range(len(self.data)):
            parts = [p[bi].long().expand(self.samples, -1, -1) for p in per_rule]
            out.append(torch.stack(parts, -1))
        return out

    # ---------------------------------------------------------------------------------------- forward
    def _round_out(self, d: _Prepared, rows: Tensor, picks: Tensor) -> Tensor:
        """Output of the synthesized round for flat rows (M,) of (S N) with their picks (M, K) -> (M, D)."""
        layer = self.policy.rounds[self.round]
        n = d.n
        valid = dedup_valid(picks)
        pk = picks.clamp(min=0)
        s_n = (rows - rows % n)[:, None]  # (M, 1): s * N
        i_idx = (rows % n)[:, None]
        # flat gathers (one index tensor each) are several times faster than 3-index advanced indexing
        lg = d.logits[self.round].reshape(-1)[rows[:, None] * n + pk]  # (M, K): l_ij of the picked j
        # softmax over the <= K picked agents, written out: torch's softmax over a last dim of size K is slow on CPU
        top = lg.masked_fill(~valid, NEG).amax(-1, keepdim=True)
        e = torch.exp((lg - top).masked_fill(~valid, float("-inf")))  # 0 outside the picks; no inf * 0
        attn = e / e.sum(-1, keepdim=True).clamp(min=1e-30)
        if d.messages is not None:
            msg = d.messages.reshape(-1, d.messages.shape[-1]).index_select(0, (rows[:, None] * n + pk).flatten())
            msg = msg.view(*pk.shape, -1)  # (M, K, D)
        else:
            o_ji = d.rel.reshape(-1, 2).index_select(0, ((s_n + pk) * n + i_idx).flatten()).view(*pk.shape, 2)
            vals = d.values.reshape(-1, d.values.shape[-1]).index_select(0, (s_n + pk).flatten()).view(*pk.shape, -1)
            msg = vals + torch.relu(layer.msg_edge(o_ji))  # (M, K, D): value of j plus its view o_ji of i
        agg = (attn.unsqueeze(-1) * msg).sum(1)
        z = layer.norm1(d.x_in.reshape(-1, d.x_in.shape[-1]).index_select(0, rows) + layer.out(agg))
        return layer.norm2(z + layer.ffn2(torch.relu(layer.ffn1(z))))

    def _l1_rows(self, d: _Prepared, rows: Tensor, picks: Tensor) -> Tensor:
        """(M,) L1 action error of the given rows (only valid for the last round)."""
        y = self._round_out(d, rows, picks)
        a = self.env.effective_action(self.policy.head(y))
        return (a - d.target.reshape(d.s * d.n, -1)[rows]).abs().sum(-1)

    def _l1_all(self, d: _Prepared, picks: Tensor) -> Tensor:
        """(S, N) L1 error of every agent; later rounds (soft attention) are recomputed in full."""
        rows = torch.arange(d.s * d.n, device=self.device)
        flat = picks.reshape(-1, picks.shape[-1])
        if self.last_round:
            return self._l1_rows(d, rows, flat).reshape(d.s, d.n)
        x = self._round_out(d, rows, flat).reshape(d.s, d.n, -1)
        for q in range(self.round + 1, self.policy.n_rounds):
            x, _ = self.policy.rounds[q].aggregate(x, d.logits[q], d.others, d.rel)
        a = self.env.effective_action(self.policy.head(x))
        return (a - d.target).abs().sum(-1)

    # ------------------------------------------------------------------------------------------ score
    @torch.no_grad()
    def score(self, rules: tuple[Rule, ...]) -> Score:
        """Objective of a program (the rules of this round); remembered until ``accept`` or the next call."""
        picks = self._program_picks(rules)
        l1_rows, l1_sum, deg_sum = [], 0.0, 0.0
        for bi, d in enumerate(self.data):
            p = picks[bi]  # (R, S, N, K)
            cur = None
            if self.current is not None and self.last_round and self.current[1][bi].shape == p.shape:
                cur = self.current
            per_sample = []
            for r in range(self.samples):
                if cur is None:
                    rows_l1 = self._l1_all(d, p[r])
                else:
                    rows_l1 = cur[2][bi][r].clone()
                    changed = (p[r] != cur[1][bi][r]).any(-1).flatten().nonzero().squeeze(-1)
                    if changed.numel():
                        flat = p[r].reshape(-1, p.shape[-1])[changed]
                        rows_l1.view(-1)[changed] = self._l1_rows(d, changed, flat)
                        self.rows_recomputed += int(changed.numel())
                per_sample.append(rows_l1)
                l1_sum += float(rows_l1.sum())
                deg_sum += float(degree_term(p[r], dedup_valid(p[r]), d.n, self.objective, self.cap).sum())
            l1_rows.append(torch.stack(per_sample))
        self.pending = (rules, picks, l1_rows)
        norm = self.total_states * self.samples
        l1, deg = l1_sum / norm, deg_sum / norm
        return Score(l1 + self.lam * deg, l1, deg)

    def accept(self) -> None:
        """Make the last scored program the base of incremental scoring."""
        self.current = self.pending

    # ---------------------------------------------------------------------------- reference scorer
    @torch.no_grad()
    def full_score(self, program: Program, chunk: int = 4096) -> Score:
        """The reference-style scorer: a full transformer forward pass over every state of D (no caches besides
        the random draws, so both scorers see the same random picks)."""
        l1_sum, deg_sum = 0.0, 0.0
        for d in self.data:
            for r in range(self.samples):
                u = None if program.deterministic else self._uniforms(d)[r]
                for s0 in range(0, d.s, chunk):
                    sl = slice(s0, min(s0 + chunk, d.s))
                    obs = Observation(d.agent[sl], d.rel[sl])
                    feats = PairFeatures(d.feats.kind, d.agent[sl], d.rel[sl], d.feats.version)
                    src = _Uniforms(u[sl]) if u is not None else None
                    masks = {}

                    def select(logits: Tensor, q: int) -> Tensor:
                        if q != self.round:
                            return ~torch.eye(d.n, dtype=torch.bool, device=logits.device).expand_as(logits)
                        picks = torch.stack([rule_picks(rule, feats, src) for rule in program.rounds[0]], -1)
                        masks["picks"] = picks
                        return picks_to_mask(picks, d.n)

                    out = self.policy(obs, select)
                    a = self.env.effective_action(out.action)
                    l1_sum += float((a - d.target[sl]).abs().sum())
                    pk = masks["picks"]
                    deg_sum += float(degree_term(pk, dedup_valid(pk), d.n, self.objective, self.cap).sum())
        norm = self.total_states * self.samples
        return Score(l1_sum / norm + self.lam * deg_sum / norm, l1_sum / norm, deg_sum / norm)
