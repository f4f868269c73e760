"""The synthesis objective of paper section 3.4, scored fast.

    J(P) = mean over states of [ sum_i ||a_i - a_i^P||_1 ] + lam * mean over states of [ max_i deg(i; c^P) ]

a is the oracle's action, a^P the action of the same transformer when each agent hears only the agents P picks
(soft attention renormalised over them, section 3.3); deg = in + out. ``objective=hinge`` uses the reference's
lam * (relu(max in - K) + relu(max out - K)) instead; ``objective=scaled`` states both terms in the dataset's own
scales, L1 / L1(silence) + lam * deg / 2K (degrees.Objective), so that one lam means the same trade-off on every task.

The scorer caches everything that does not depend on the program (state embeddings, attention logits, value
vectors, features, and the uniforms of random rules: common random numbers), evaluates only the rules a
proposal changed (each rule's picks are cached), and recomputes the action only for the agents whose set of
picked agents changed, aggregating over the <= K picked agents instead of all N. ``full_score`` is the
reference-style scorer (a full forward pass of the transformer over D) used to check it and to benchmark it.

On a CPU with numba (``backend=auto``), two parts run as compiled kernels (``kernels.py``): a rule's picks scan
each agent's candidates in a precomputed order (by score feature, or by a random rule's uniforms) and stop at the
first one the filter passes, instead of testing all N^2 pairs; and a proposal's bookkeeping (which agents'
sets changed, memo, degree counts) is one pass over the agents instead of some fifty tensor operations.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor

from ..dsl.ast import Program, RandomRule, Rule
from ..degrees import objective_form
from ..dsl.interpret import dedup_valid, picks_to_mask, rule_picks
from ..tasks.base import Observation, Task, applied_action
from ..policy.transformer import CommTransformer
from . import kernels
from .dataset import DataBucket
from .prepared import Prepared


@dataclass(frozen=True)
class Score:
    total: float
    l1: float  # mean over states of sum_i ||a_i - a^P_i||_1
    degree: float  # mean over states of the degree term, before lam


@dataclass(frozen=True)
class Scale:
    """The dataset's own units of the two terms (``objective=scaled``): L1 of the oracle's silent self on D (every
    agent hears nobody in the searched round; the action gap that communication can close) and the reference degree
    2K (max in+out when every agent hears K others and is heard by K)."""

    l1: float
    degree: float

    def pair(self) -> tuple[float, float]:
        return (self.l1, self.degree)


class _Uniforms:
    """A UniformSource that returns fixed draws (common random numbers across proposals)."""

    def __init__(self, u: Tensor):
        self.u = u

    def rand(self, batch: int, *shape: int) -> Tensor:
        return self.u


def degree_counts(picks: Tensor, valid: Tensor, n: int) -> tuple[Tensor, Tensor]:
    """picks, valid: (S, N, K) -> in- and out-degree (S, N) int32 of every agent (self edges never picked)."""
    s = picks.shape[0]
    deg_in = valid.sum(-1, dtype=torch.int32)
    idx = torch.where(valid, picks, n).flatten(1)  # (S, N K); invalid picks land in column n
    deg_out = torch.zeros(s, n + 1, dtype=torch.int32, device=picks.device)
    deg_out.scatter_add_(1, idx, torch.ones_like(idx, dtype=torch.int32))
    return deg_in, deg_out[:, :n]


def degree_from_counts(deg_in: Tensor, deg_out: Tensor, objective: str, cap: int) -> Tensor:
    """(S, N) in/out degrees -> (S,) the per-state degree term: max_i (in + out), or the reference's hinges."""
    if objective == "hinge":
        return (torch.relu(deg_in.amax(-1) - cap) + torch.relu(deg_out.amax(-1) - cap)).float()
    return (deg_in + deg_out).amax(-1).float()


def degree_term(picks: Tensor, valid: Tensor, n: int, objective: str, cap: int) -> Tensor:
    """picks, valid: (S, N, K) -> (S,) the per-state degree term."""
    return degree_from_counts(*degree_counts(picks, valid, n), objective, cap)


@dataclass
class _Current:
    """The accepted program of one bucket and one random sample: each rule's picks, per-row L1 and degrees."""

    picks: list[Tensor]  # per rule (S N,) int8 (int16 beyond 127 agents) views of cached picks
    table: Tensor  # (S N, K) the same picks, one row per agent
    l1: Tensor  # (S N,) L1 action error per agent
    deg_in: Tensor  # (S N,) int32
    deg_out: Tensor  # (S N,) int32
    l1_sum: float
    deg_sum: float
    x: Tensor | None = None  # (S N, D) output of the synthesized round, when later rounds follow it


class CachedScorer:
    """Incremental scorer of programs for one communication round (paper appendix A: one program per round)."""

    def __init__(self, policy: CommTransformer, env: Task, buckets: list[DataBucket], *,
                 round_idx: int, version: str, lam: float, objective: str, cap: int, samples: int,
                 gen: torch.Generator, device: torch.device, cache_size: int = 256, backend: str = "auto",
                 scale: Scale | None = None):
        self.policy = policy.eval()
        # compiled bookkeeping and rule scans on CPU; torch elsewhere (GPUs, no numba) and as the reference
        self.compiled = kernels.use_compiled(backend, device)
        self.env, self.round, self.lam, self.objective, self.cap = env, round_idx, lam, objective, cap
        self.applied = applied_action(env)  # (action, agent) -> the action as the task applies it
        self.form = objective_form(objective)
        self.samples, self.device = samples, device
        # every (bucket, rule position, sample) draws its uniforms from its own seed: random rules at different
        # positions are independent, as at run time, and the draws do not depend on the search path
        self.uniform_seed = int(torch.randint(0, 2**62, (1,), generator=gen))
        self.last_round = round_idx == policy.n_rounds - 1
        with torch.no_grad():
            self.fmap = env.features(version)  # the task's feature map the programs read (version v1, v2)
            self.data = [Prepared(policy, self.fmap, b, round_idx, device, memo=self.last_round)
                         for b in buckets]
        self.total_states = sum(d.s for d in self.data)
        self.rule_cache: OrderedDict[tuple, list[Tensor]] = OrderedDict()
        self.cache_size = cache_size
        self.current: tuple[tuple, list[list[_Current]]] | None = None  # (rule keys, per bucket per sample)
        self.pending: tuple[tuple, list[list[_Current]]] | None = None
        self.rows_recomputed = 0  # agents whose action was recomputed (incremental scoring)
        self.memo_hits = 0  # agents whose L1 came from the memo of earlier sets
        # the scaled objective's units: given (a coarse scorer takes the whole of D's), else measured on this D
        self.scale = scale if scale is not None else (self.measure_scale() if self.form.scaled else None)

    def measure_scale(self) -> Scale:
        """The units of ``objective=scaled`` on this D: (L1 of silence, 2K); a D where silence loses nothing (the
        oracle ignores its messages) is refused, since no program could then improve on silence."""
        l1 = self.silent_l1()
        size = sum(float(d.target_flat.abs().sum()) for d in self.data) / self.total_states  # mean sum_i ||a_i||_1
        if not l1 > 1e-6 * size:  # zero up to rounding: the cached and the full forward pass differ in last digits
            from ..errors import UserError

            raise UserError("synth.objective=scaled: the oracle's actions do not change when it hears nobody (L1 of "
                            "silence on D is 0), so there is nothing to trade; use synth.objective=paper")
        return Scale(l1, 2.0 * self.cap)

    @torch.no_grad()
    def silent_l1(self) -> float:
        """Mean over states of sum_i ||a_i - a_i^silent||_1: the oracle against itself hearing nobody in this round
        (the other rounds keep soft attention). Touches no cache, so it moves no search."""
        total = 0.0
        for d in self.data:
            rows = torch.arange(d.s * d.n, device=self.device)
            none = torch.full((d.s * d.n, self.cap), -1, dtype=torch.long, device=self.device)
            valid = torch.zeros_like(none, dtype=torch.bool)
            if self.last_round:
                total += float(self._l1_rows(d, rows, none, valid).sum())
            else:
                total += float(self._l1_later(d, self._round_out(d, rows, none, valid)).sum())
        return total / self.total_states

    def _total(self, l1: float, deg: float) -> float:
        """The objective from its terms (the paper's form: l1 + lam * deg, as always)."""
        return self.form.total(l1, deg, self.lam, self.scale.pair() if self.scale is not None else (1.0, 1.0))

    # ------------------------------------------------------------------------------------------ picks
    def _uniforms(self, bi: int, position: int, sample: int) -> Tensor:
        """(S, N, N) common random numbers of the random rule at ``position`` in bucket ``bi``."""
        d = self.data[bi]
        if (position, sample) not in d.uniforms:
            g = torch.Generator().manual_seed(self.uniform_seed + 1_000_003 * bi + 1009 * position + sample)
            d.uniforms[(position, sample)] = torch.rand(d.s, d.n, d.n, generator=g).to(self.device)
        return d.uniforms[(position, sample)]

    @staticmethod
    def _key(rule: Rule, position: int) -> tuple:
        # a random rule's picks depend on its position's random numbers; an argmax rule's do not
        return (rule, position) if isinstance(rule, RandomRule) else (rule, -1)

    def picks_of(self, rule: Rule, position: int = 0) -> list[Tensor]:
        """Per bucket (R, S N) picks (pick_dtype) of one rule (R = samples for random rules, else 1); cached."""
        key = self._key(rule, position)
        if key in self.rule_cache:
            self.rule_cache.move_to_end(key)
            return self.rule_cache[key]
        spec = None  # the rule compiled once for kernels.scan_picks (feature names are the same in every bucket)
        if self.compiled:
            spec = kernels.rule_spec(rule, *self.data[0].scan_inputs()[:2])
        out = []
        for bi, d in enumerate(self.data):
            if spec is not None:
                out.append(self._compiled_picks(bi, spec, position))
                continue
            if isinstance(rule, RandomRule):
                ps = [rule_picks(rule, d.feats, _Uniforms(self._uniforms(bi, position, r)))
                      for r in range(self.samples)]
            else:
                ps = [rule_picks(rule, d.feats, None)]
            out.append(torch.stack(ps).to(d.pick_dtype).flatten(1))
        self.rule_cache[key] = out
        if len(self.rule_cache) > self.cache_size:
            self.rule_cache.popitem(last=False)
        return out

    def _compiled_picks(self, bi: int, spec: kernels.RuleSpec, position: int) -> Tensor:
        """(R, S N) picks (pick_dtype) of one compiled rule in bucket bi, by kernels.scan_picks."""
        d = self.data[bi]
        _, _, fp, fa = d.scan_inputs()
        random_rule = spec.order is not None and spec.order[0] == "random"
        out = torch.empty(self.samples if random_rule else 1, d.s * d.n, dtype=d.pick_dtype)
        for r in range(out.shape[0]):
            if spec.order is None:
                order = None  # index order
            elif random_rule:
                order = d.order(("random", position, r), self._uniforms(bi, position, r))
            else:
                order = d.order(spec.order)
            kernels.scan_picks(spec, pair_feats=fp, agent_feats=fa, n=d.n, order=order, out=out[r].numpy())
        return out

    # ---------------------------------------------------------------------------------------- forward
    def _round_out(self, d: Prepared, rows: Tensor, picks: Tensor, valid: Tensor) -> Tensor:
        """Output of the synthesized round for flat rows (M,) of (S N) with their picks and valid (M, K) -> (M, D)."""
        layer = self.policy.rounds[self.round]
        n = d.n
        pk = picks.clamp(min=0)
        # flat gathers (one index tensor each) are several times faster than 3-index advanced indexing
        pair = (rows[:, None] * n + pk).flatten()  # (M K,) flat index of pair (s, i, j)
        lg = d.logits_flat.index_select(0, pair).view(pk.shape)  # (M, K): l_ij of the picked j
        if d.messages is not None:
            msg = d.messages.index_select(0, pair).view(*pk.shape, -1)  # (M, K, D) messages projected by W_o
        else:
            s_n = (rows - rows % n)[:, None]  # (M, 1): s * N
            pair_rows = d.rel.reshape(-1, d.rel.shape[-1])  # (S N N, Dp): Dp is the task's pair_dim
            o_ji = pair_rows.index_select(0, ((s_n + pk) * n + (rows % n)[:, None]).flatten())
            vals = d.values.reshape(-1, d.values.shape[-1]).index_select(0, (s_n + pk).flatten())
            msg = F.linear(layer.message(vals, o_ji), layer.out.weight).view(*pk.shape, -1)
        # the policy's own attention over the picked agents (section 3.3), on cached logits and projected messages;
        # base = x + b_o, so finish(base + sum_k a_k W_o m_k) is the round output (the policy is in eval mode)
        agg, _ = layer.attend(lg, valid, msg)  # (M, D)
        return layer.finish(d.base.index_select(0, rows) + agg)

    def _l1_rows(self, d: Prepared, rows: Tensor, picks: Tensor, valid: Tensor) -> Tensor:
        """(M,) L1 action error of the given rows (only valid for the last round)."""
        y = self._round_out(d, rows, picks, valid)
        a = self.applied(self.policy.head(y), d.agent_flat.index_select(0, rows))
        return (a - d.target_flat.index_select(0, rows)).abs().sum(-1)

    def _l1_later(self, d: Prepared, x: Tensor) -> Tensor:
        """(S N, D) output of the synthesized round -> (S N,) L1 error after the later (soft) rounds."""
        y = x.view(d.s, d.n, -1)
        for (a, c), layer in zip(d.later, self.policy.rounds[self.round + 1:]):
            y = layer._post(y, torch.bmm(a, layer.value(y)) + c)
        out = self.applied(self.policy.head(y), d.agent)
        return (out - d.target).abs().sum(-1).flatten()

    # ------------------------------------------------------------------------------------------ score
    def _full(self, d: Prepared, picks: list[Tensor]) -> _Current:
        p = torch.stack(picks, -1).long()  # (S N, K)
        valid = dedup_valid(p)
        rows = torch.arange(d.s * d.n, device=self.device)
        x = None
        if self.last_round:
            l1 = self._l1_rows(d, rows, p, valid)
            d.remember(rows, d.set_key(p, valid), l1)
        else:
            x = self._round_out(d, rows, p, valid)
            l1 = self._l1_later(d, x)
        deg_in, deg_out = degree_counts(p.view(d.s, d.n, -1), valid.view(d.s, d.n, -1), d.n)
        deg = degree_from_counts(deg_in, deg_out, self.objective, self.cap)
        return _Current(picks, p.to(d.pick_dtype), l1, deg_in.flatten(), deg_out.flatten(), float(l1.sum()),
                        float(deg.sum()), x)

    def _incremental_compiled(self, d: Prepared, cur: _Current, picks: list[Tensor], changed: list[int]) -> _Current:
        """``_incremental`` with the bookkeeping in one compiled pass over the agents (kernels.incremental_rows);
        only the forward pass of the agents whose set changed (and, before the last round, the later rounds)
        stays in torch."""
        table, l1 = cur.table.clone(), cur.l1.clone()
        deg_in, deg_out = cur.deg_in.clone(), cur.deg_out.clone()
        r_total, k_rules = table.shape
        if d.todo is None:  # per-bucket scratch: rows, picks, valid and set names of the agents to recompute
            d.todo = (torch.empty(r_total, dtype=torch.int64), torch.empty(r_total, k_rules, dtype=torch.int64),
                      torch.empty(r_total, k_rules, dtype=torch.bool), torch.empty(r_total, dtype=torch.int64))
        rows, new, valid, keys = d.todo
        new_cols = torch.stack([picks[k] for k in changed])  # (C, R)
        m, hits = kernels.incremental_rows(  # the memo is empty (no slots) before the last round
            new_cols.numpy(), np.asarray(changed, dtype=np.int64), table=table.numpy(), n=d.n, codes=d.codes.numpy(),
            memo_key=d.memo_key.numpy(), memo_l1=d.memo_l1.numpy(), l1=l1.numpy(), deg_in=deg_in.numpy(),
            deg_out=deg_out.numpy(), todo_rows=rows.numpy(), todo_picks=new.numpy(), todo_valid=valid.numpy(),
            todo_keys=keys.numpy())
        x = cur.x
        if m and self.last_round:
            fresh = self._l1_rows(d, rows[:m], new[:m], valid[:m])
            kernels.store_rows(rows[:m].numpy(), keys[:m].numpy(), fresh.numpy(), l1.numpy(), d.memo_key.numpy(),
                               d.memo_l1.numpy())
        elif m:
            assert x is not None
            x = x.clone()
            x[rows[:m]] = self._round_out(d, rows[:m], new[:m], valid[:m])
            l1 = self._l1_later(d, x)
        self.rows_recomputed += m
        self.memo_hits += hits
        deg = kernels.degree_sum(deg_in.numpy(), deg_out.numpy(), d.n, self.objective == "hinge", self.cap)
        return _Current(picks, table, l1, deg_in, deg_out, float(l1.sum()), float(deg), x)

    def _incremental(self, d: Prepared, cur: _Current, picks: list[Tensor], changed: list[int]) -> _Current:
        """Only the agents whose pick of a changed rule differs are recomputed (their round output, and their L1
        and degree counts). Before the last round, a changed agent is heard by everybody in the next round, so the
        later rounds are rerun on every agent, from the cached weights of ``Prepared.later``."""
        diff = picks[changed[0]] != cur.picks[changed[0]]
        for k in changed[1:]:
            diff |= picks[k] != cur.picks[k]
        rows = diff.nonzero().squeeze(-1)  # (M,) flat (s, i)
        if rows.numel() == 0:
            return _Current(picks, cur.table, cur.l1, cur.deg_in, cur.deg_out, cur.l1_sum, cur.deg_sum, cur.x)
        table = cur.table.clone()
        for k in changed:
            table[:, k] = picks[k]
        old = cur.table.index_select(0, rows).long()  # (M, K)
        new = table.index_select(0, rows).long()
        new_valid, old_valid = dedup_valid(new), dedup_valid(old)
        key = d.set_key(new, new_valid)
        same = key == d.set_key(old, old_valid)  # another rule already picked the new agent: same set
        x = cur.x
        if self.last_round:
            l1 = cur.l1.clone()
            hit, known = d.recall(rows, key)
            hit &= ~same
            todo = ~(same | hit)
            l1[rows[hit]] = known[hit]
            if bool(todo.any()):
                fresh = self._l1_rows(d, rows[todo], new[todo], new_valid[todo])
                l1[rows[todo]] = fresh
                d.remember(rows[todo], key[todo], fresh)
            self.memo_hits += int(hit.sum())
        else:
            todo = ~same
            assert x is not None
            if bool(todo.any()):
                x = x.clone()
                x[rows[todo]] = self._round_out(d, rows[todo], new[todo], new_valid[todo])
                l1 = self._l1_later(d, x)
            else:
                l1 = cur.l1
        self.rows_recomputed += int(todo.sum())
        deg_in = cur.deg_in.clone()
        deg_in[rows] = new_valid.sum(-1, dtype=torch.int32)
        # out-degree: the old picks of these rows lose one listener each, the new picks gain one
        s_n = (rows - rows % d.n)[:, None]
        deg_out = cur.deg_out.clone()
        deg_out.index_add_(0, (s_n + old.clamp(min=0))[old_valid], torch.full((int(old_valid.sum()),), -1,
                                                                                dtype=torch.int32))
        deg_out.index_add_(0, (s_n + new.clamp(min=0))[new_valid], torch.ones(int(new_valid.sum()),
                                                                               dtype=torch.int32))
        deg = degree_from_counts(deg_in.view(d.s, d.n), deg_out.view(d.s, d.n), self.objective, self.cap)
        return _Current(picks, table, l1, deg_in, deg_out, float(l1.sum()), float(deg.sum()), x)

    @torch.no_grad()
    def score(self, rules: tuple[Rule, ...]) -> Score:
        """Objective of a program (the rules of this round); remembered until ``accept`` or the next call."""
        keys = tuple(self._key(r, k) for k, r in enumerate(rules))
        per_rule = [self.picks_of(r, k) for k, r in enumerate(rules)]
        changed = None
        if self.current is not None and len(self.current[0]) == len(keys):
            changed = [k for k in range(len(keys)) if keys[k] != self.current[0][k]]
        states: list[list[_Current]] = []
        l1_sum, deg_sum = 0.0, 0.0
        for bi, d in enumerate(self.data):
            per_sample = []
            for r in range(self.samples):
                picks = [p[bi][min(r, p[bi].shape[0] - 1)] for p in per_rule]  # deterministic rules broadcast
                if changed is None:
                    c = self._full(d, picks)
                elif changed and self.compiled:
                    c = self._incremental_compiled(d, self.current[1][bi][r], picks, changed)  # type: ignore[index]
                elif changed:
                    c = self._incremental(d, self.current[1][bi][r], picks, changed)  # type: ignore[index]
                else:
                    c = self.current[1][bi][r]  # type: ignore[index]
                per_sample.append(c)
                l1_sum += c.l1_sum
                deg_sum += c.deg_sum
            states.append(per_sample)
        self.pending = (keys, states)
        norm = self.total_states * self.samples
        l1, deg = l1_sum / norm, deg_sum / norm
        return Score(self._total(l1, deg), l1, deg)

    def accept(self) -> None:
        """Make the last scored program the base of incremental scoring."""
        self.current = self.pending

    def degree_stats(self) -> dict[str, float]:
        """max in and max out of the last scored program: mean over the states of D (and random samples) of the
        most agents one agent hears / is heard by."""
        assert self.pending is not None, "score a program first"
        sums = {"max_in": 0.0, "max_out": 0.0}
        for d, per_sample in zip(self.data, self.pending[1]):
            for c in per_sample:
                sums["max_in"] += float(c.deg_in.view(d.s, d.n).amax(-1).sum())
                sums["max_out"] += float(c.deg_out.view(d.s, d.n).amax(-1).sum())
        return {k: v / (self.total_states * self.samples) for k, v in sums.items()}

    # ---------------------------------------------------------------------------- reference scorer
    @torch.no_grad()
    def full_score(self, program: Program, pairs: int = 4_000_000) -> Score:
        """The reference-style scorer: a full transformer forward pass over every state of D (no caches besides
        the random draws, so both scorers see the same random picks), in chunks of about ``pairs`` agent pairs."""
        l1_sum, deg_sum = 0.0, 0.0
        for bi, d in enumerate(self.data):
            chunk = max(1, pairs // (d.n * d.n))
            for r in range(self.samples):
                for s0 in range(0, d.s, chunk):
                    sl = slice(s0, min(s0 + chunk, d.s))
                    obs = Observation(d.agent[sl], d.rel[sl])
                    feats = self.fmap.view(d.agent[sl], d.rel[sl])
                    masks = {}

                    def select(logits: Tensor, q: int) -> Tensor:
                        if q != self.round:
                            return ~torch.eye(d.n, dtype=torch.bool, device=logits.device).expand_as(logits)
                        picks = torch.stack([
                            rule_picks(rule, feats, _Uniforms(self._uniforms(bi, k, r)[sl])
                                       if isinstance(rule, RandomRule) else None)
                            for k, rule in enumerate(program.rounds[0])], -1)
                        masks["picks"] = picks
                        return picks_to_mask(picks, d.n)

                    out = self.policy(obs, select)
                    a = self.applied(out.action, d.agent[sl])
                    l1_sum += float((a - d.target[sl]).abs().sum())
                    pk = masks["picks"]
                    deg_sum += float(degree_term(pk, dedup_valid(pk), d.n, self.objective, self.cap).sum())
        norm = self.total_states * self.samples
        return Score(self._total(l1_sum / norm, deg_sum / norm), l1_sum / norm, deg_sum / norm)
