"""A program's filter scan over a large team without the (B, N, N) features (the sparse path, tasks/pairs.py).

The rules of a program read features of every pair (i, j) to decide whom i asks (paper section 3.2): that scan is
the one quadratic part left under a program. It runs without gradients (picks are indices), in one of two ways:

* **fused** (a CPU with numba, the observation an ``Offsets`` pair source, every pair feature the round reads
  declared with its ``Source``): ``policy/scan_kernels.py`` computes o_ij, the features, every filter and score and
  a running best per rule pair by pair, O(N) memory and no temporaries (3-4.5x the reference's speed from 1,000
  agents on, docs/performance.md section 15). The program is compiled here into the kernel's arrays (``compile_round``).
* **reference** (anything else: GPUs, no numba, features only the task's function knows): chunks of receivers, each
  chunk's features built from the pair source's rows and dropped before the next, so its memory is bounded by
  ``tasks.pairs.PAIR_CHUNK`` pairs whatever N is.

Both give the same picks (tests/test_scan.py). A random rule's uniforms come from counters (``counter_uniform`` of
a key per rule and episode drawn from the bucket's random source, and i N + j), so the picks depend neither on the
chunk size nor on the way the scan runs.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import torch
from torch import Tensor

from ..dsl.ast import And, ArgMaxRule, Cond, Linear, Or, Program, RandomRule, Test, TrueCond
from ..dsl.interpret import program_picks
from ..tasks.base import Observation, Rng
from ..tasks.features import FeatureMap
from ..tasks.pairs import Offsets, _box_muller_tables, _numba_on, rows_per_chunk, uniform_rows

MAX_TERMS = 8
"""terms of a linear form the fused kernel takes (its close-call margin covers their roundings)"""
MAX_WEIGHT = 1e15
"""the largest weight of a score or a test the fused kernels take (bounded features times it stay far from the
reference's -1e30 sentinel and from float32's overflow)"""
FUSED = True
"""take the fused kernel where it applies (False: always the reference scan; benchmarks and tests compare them)"""
CELLS_FROM = 256
"""team size from which the fused scan decides by cells (policy/scan_cells.py; below, every pair is computed)"""


class _RowUniforms:
    """The uniforms of a chunk of receivers: the k-th ``rand`` call of a chunk serves the round's k-th random rule
    (program_picks evaluates the rules in order, each random rule drawing once)."""

    def __init__(self, keys: list[Tensor], first: int, stop: int, n: int):
        self.keys, self.first, self.stop, self.n, self.calls = keys, first, stop, n, 0

    def rand(self, batch: int, rows: int, n: int) -> Tensor:
        key = self.keys[self.calls]
        self.calls += 1
        return uniform_rows(key, self.first, self.stop, self.n)  # (B, R, N)


def scan_program(program: Program, round: int, fmap: FeatureMap, obs: Observation, rng: Rng) -> Tensor:
    """(B, N, K) long: the agent each rule of program round ``round`` picks for each agent (-1 for nobody), from
    an observation given as a pair source (``obs.pairs``), under no_grad."""
    assert obs.pairs is not None, "scan_program reads a pair source (tasks/pairs.py Offsets)"
    b, n = obs.agent.shape[:2]
    keys = [rng.keys(b) for r in program.rounds[round] if isinstance(r, RandomRule)]  # one per random rule
    with torch.no_grad():
        compiled = compile_round(program, round, fmap) if FUSED and _fusable(obs) else None
        if compiled is not None:
            return _scan_fused(compiled, fmap, obs, keys)
        c = rows_per_chunk(b, n)
        out = []
        for i in range(0, n, c):
            stop = min(i + c, n)
            feats = fmap.view(obs.agent[:, i:stop], obs.pairs.rows(i, stop), first=i)
            out.append(program_picks(program, round, feats, _RowUniforms(keys, i, stop, n)))
        return torch.cat(out, 1)


def _fusable(obs: Observation) -> bool:
    """Whether the observation is one the fused kernel reads: counter-noise offsets of float32 positions on a CPU
    with numba (imported only then: the CLI's start-up does not pay for numba)."""
    p = obs.pairs
    return isinstance(p, Offsets) and p.pos.dtype == torch.float32 and _numba_on(p.pos)


@dataclass(frozen=True)
class CompiledRound:
    """A program round as the arrays ``scan_kernels.program_scan`` reads (its docstring has the layout)."""

    agent: tuple[str, ...]  # agent feature names, ids P + a
    pair: dict  # pk, psign, pa, pb
    rules: dict  # kind, sf, sw, sn, code, arg, clen, tf, tw, tn, thr
    random: tuple[int, ...]  # rule index of each random rule, in order


def compile_round(program: Program, round: int, fmap: FeatureMap) -> CompiledRound | None:
    """The round in the fused kernel's form; None when a pair feature it reads has no source the kernel computes
    (o_ij's x, y, norm or angle, times a sign, or a product of such features and agent features). Compiled once per
    program round and feature declaration (every step of a rollout asks again)."""
    return _compile(program, round, fmap.vocab)


@lru_cache(maxsize=64)
def _compile(program: Program, round: int, vocab) -> CompiledRound | None:
    from . import scan_kernels as sk

    rules = program.rounds[round]
    pair: list[tuple[int, float, int, int]] = []
    pair_ids: dict[str, int] = {}
    agent: list[str] = []
    parts = {"x": sk.X, "y": sk.Y, "d": sk.D, "theta": sk.THETA}

    def ident(name: str) -> int | None:  # a feature's id, adding it (and its factors) to the tables
        if name not in vocab.names:
            return None
        if vocab.agent_level(name):
            src = vocab.get(name).source  # computed below from s_i alone: only a source that reads s_i says so
            if src is None or not (src.field == "agent" or (src.product and all(
                    f in vocab.names and vocab.agent_level(f) and ident(f) is not None for f in src.product))):
                return None
            if name not in agent:
                agent.append(name)
            return -1 - agent.index(name)  # agent ids are remapped to P + a once P is known
        if name in pair_ids:
            return pair_ids[name]
        s = vocab.get(name).source
        if s is None:
            return None
        if s.product:
            if len(s.product) != 2:
                return None
            a, b = ident(s.product[0]), ident(s.product[1])
            if a is None or b is None:
                return None
            entry = (sk.PRODUCT, 1.0, a, b)
        elif s.field == "rel" and s.start == 0 and s.part in parts:
            entry = (parts[s.part], -1.0 if s.sign < 0 else 1.0, 0, 0)
        else:
            return None
        pair.append(entry)
        pair_ids[name] = len(pair) - 1
        return pair_ids[name]

    def linear(f: Linear) -> list[tuple[int, float]] | None:
        if len(f.terms) > MAX_TERMS:
            return None  # scan_kernels._margin bounds the roundings of up to MAX_TERMS terms
        if any(abs(w) > MAX_WEIGHT for _, w in f.terms):
            return None  # terms near float32's overflow: the reference's arithmetic decides those
        out = []
        for name, w in f.terms:
            k = ident(name)
            if k is None:
                return None
            out.append((k, w))
        return out

    tests: list[list[list[tuple[int, float]]]] = []
    thresholds: list[list[float]] = []
    codes: list[list[tuple[int, int]]] = []
    scores: list[list[tuple[int, float]]] = []

    def postfix(c: Cond, code: list, ts: list, thr: list) -> bool:
        if isinstance(c, TrueCond):
            code.append((sk.TRUE, 0))
        elif isinstance(c, Test):
            terms = linear(c.lhs)
            if terms is None:
                return False
            code.append((sk.TEST, len(ts)))
            ts.append(terms)
            thr.append(c.threshold)
        elif isinstance(c, (And, Or)):
            if not (postfix(c.left, code, ts, thr) and postfix(c.right, code, ts, thr)):
                return False
            code.append((sk.AND if isinstance(c, And) else sk.OR, 0))
        else:
            return False
        return True

    for r in rules:
        if not isinstance(r, (ArgMaxRule, RandomRule)):
            return None  # the reference names what it is not
        code: list = []
        ts: list = []
        thr: list = []
        if not postfix(r.cond, code, ts, thr):
            return None
        score = linear(r.score) if isinstance(r, ArgMaxRule) else []
        if score is None:
            return None
        codes.append(code)
        tests.append(ts)
        thresholds.append(thr)
        scores.append(score)
    n_pair = len(pair)
    for kind_, _, a, b in list(pair):  # an angle that is a factor of a product: atan2f for every pair
        for f in (a, b) if kind_ == sk.PRODUCT else ():
            if f >= 0 and pair[f][0] == sk.THETA:
                pair[f] = (sk.THETA_EXACT,) + pair[f][1:]

    def remap(k: int) -> int:
        return k if k >= 0 else n_pair + (-1 - k)

    k_rules = len(rules)
    t_max = max([len(s) for s in scores] + [len(t) for ts in tests for t in ts] + [1])
    m_max = max([len(ts) for ts in tests] + [1])
    l_max = max([len(c) for c in codes] + [1])
    sf = np.zeros((k_rules, t_max), np.int64)
    sw = np.zeros((k_rules, t_max), np.float32)
    sn = np.zeros(k_rules, np.int64)
    code_a = np.zeros((k_rules, l_max), np.int64)
    arg_a = np.zeros((k_rules, l_max), np.int64)
    clen = np.zeros(k_rules, np.int64)
    tf = np.zeros((k_rules, m_max, t_max), np.int64)
    tw = np.zeros((k_rules, m_max, t_max), np.float32)
    tn = np.zeros((k_rules, m_max), np.int64)
    thr_a = np.zeros((k_rules, m_max), np.float32)  # torch compares float32 values with the threshold in float32
    for k in range(k_rules):
        for t, (f, w) in enumerate(scores[k]):
            sf[k, t], sw[k, t] = remap(f), w
        sn[k] = len(scores[k])
        for s, (op, a) in enumerate(codes[k]):
            code_a[k, s], arg_a[k, s] = op, a
        clen[k] = len(codes[k])
        for m, terms in enumerate(tests[k]):
            for t, (f, w) in enumerate(terms):
                tf[k, m, t], tw[k, m, t] = remap(f), w
            tn[k, m] = len(terms)
            thr_a[k, m] = thresholds[k][m]
    pk = np.array([e[0] for e in pair], np.int64)
    psign = np.array([e[1] for e in pair], np.float32)
    pa = np.array([remap(e[2]) for e in pair], np.int64)
    pb = np.array([remap(e[3]) for e in pair], np.int64)
    kind = np.array([0 if isinstance(r, ArgMaxRule) else 1 for r in rules], np.int64)
    return CompiledRound(tuple(agent), dict(pk=pk, psign=psign, pa=pa, pb=pb),
                         dict(kind=kind, sf=sf, sw=sw, sn=sn, code=code_a, arg=arg_a, clen=clen, tf=tf, tw=tw, tn=tn,
                              thr=thr_a),
                         tuple(k for k, r in enumerate(rules) if isinstance(r, RandomRule)))


def _scan_fused(c: CompiledRound, fmap: FeatureMap, obs: Observation, keys: list[Tensor]) -> Tensor:
    """(B, N, K) long picks by the fused kernel: one call per episode, or per share of its receivers when torch may use
    several threads (the kernel releases the GIL)."""
    from . import scan_kernels as sk

    pairs = obs.pairs
    b, n = obs.agent.shape[:2]
    k_rules = len(c.rules["kind"])
    # the agent features in torch (O(N)), by the task's own functions; they read s_i only, never o_ij
    view = fmap.view(obs.agent, torch.zeros(()).expand(b, n, n, 2))
    fa = (torch.stack([view[a].reshape(b, n) for a in c.agent], 1).float().contiguous() if c.agent
          else torch.zeros(b, 0, n))  # (B, A, N)
    pos = pairs.pos.detach().contiguous().numpy()
    radius, cossin = _tables()
    noise = pairs.key.tolist() if pairs.noise_std > 0 else [0] * b
    out = torch.empty(b, n, k_rules, dtype=torch.long)
    klo = np.zeros((b, k_rules), np.int64)
    khi = np.zeros((b, k_rules), np.int64)
    for rule, key in zip(c.random, keys):
        for e, v in enumerate(key.tolist()):
            klo[e, rule], khi[e, rule] = v & 0x7FFFFFFF, (v >> 31) & 0x7FFFFFFF
    fa_np, out_np = fa.numpy(), out.numpy()
    by_cells = n >= CELLS_FROM and bool(np.isfinite(pos).all())
    if by_cells:
        from . import scan_cells

        # |o_ij - (p_j - p_i)| per axis is at most sigma times the table's largest radius; plus float32 rounding
        reach = np.float64(pairs.noise_std * float(radius.max()) * (1 + 1e-6) + 1e-5 * (1 + float(np.abs(pos).max())))

    def run(e: int, first: int, stop: int) -> None:
        args = (pos[e], np.int64(noise[e] & 0x7FFFFFFF), np.int64((noise[e] >> 31) & 0x7FFFFFFF),
                np.float32(pairs.noise_std), radius, cossin, np.int64(first), fa_np[e],
                c.pair["pk"], c.pair["psign"], c.pair["pa"], c.pair["pb"],
                c.rules["kind"], klo[e], khi[e], c.rules["sf"], c.rules["sw"], c.rules["sn"],
                c.rules["code"], c.rules["arg"], c.rules["clen"], c.rules["tf"], c.rules["tw"], c.rules["tn"],
                c.rules["thr"], out_np[e, first:stop])
        if by_cells:
            scan_cells.cell_scan(*args, reach)
        else:
            sk.program_scan(*args)

    workers = torch.get_num_threads()
    if workers <= 1 or b * n * n < PARALLEL_FROM:
        for e in range(b):
            run(e, 0, n)
        return out
    # the kernel releases the GIL: the threads torch may use share the receivers (the picks do not depend on it)
    per = -(-b * n // workers)
    parts = [(e, i, min(i + per, n)) for e in range(b) for i in range(0, n, per)]
    list(_pool(workers).map(lambda p: run(*p), parts))
    return out


@lru_cache(maxsize=1)
def _tables() -> tuple[np.ndarray, np.ndarray]:
    """The Box-Muller tables as the kernel reads them: radius (65536,) and cos, sin side by side (65536, 2), one
    cache line per look-up."""
    radius, cos, sin = _box_muller_tables("cpu")
    return radius.numpy(), torch.stack([cos, sin], 1).numpy()


PARALLEL_FROM = 1 << 20
"""pairs from which the fused scan shares its receivers among torch's threads (below, one thread is quicker)"""
_POOLS: dict = {}


def _pool(workers: int):
    from concurrent.futures import ThreadPoolExecutor

    if workers not in _POOLS:
        _POOLS[workers] = ThreadPoolExecutor(workers, thread_name_prefix="neurosym-scan")
    return _POOLS[workers]
