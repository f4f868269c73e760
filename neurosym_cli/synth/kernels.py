"""Compiled CPU kernels of the incremental scorer (numba), for the work eager torch does badly: per-agent
bookkeeping of a proposal (which agents' picked sets changed, memo look-ups, degree counts) and rule evaluation
that scans each agent's candidates in a precomputed order and stops at the first one its filter passes.

Every kernel computes exactly what the torch code of ``objective.py`` and ``dsl/interpret.py`` computes (the
tests compare them); the torch path stays the reference and serves GPUs and machines without numba.
Shapes: R = S N flat agent rows of a bucket, K rules, N agents, C changed rules.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..dsl.ast import And, Or, RandomRule, Rule, Test, TrueCond, rule_features

try:  # numba is a dependency, but the scorer falls back to torch where it cannot be imported
    from numba import njit

    AVAILABLE = True
except ImportError:  # pragma: no cover - exercised only on machines without numba
    AVAILABLE = False

    def njit(*args, **kwargs):  # type: ignore[no-redef]
        return lambda f: f


def use_compiled(backend: str, device) -> bool:
    """Whether the scorer runs these kernels for ``synth.backend`` (auto, numba, torch) on ``device``: auto takes
    them on a CPU with numba; numba insists on them (a one-line error where they cannot run)."""
    from ..config import ConfigError

    if backend == "numba" and not AVAILABLE:
        raise ConfigError("synth.backend=numba needs numba (pip install numba), or use synth.backend=auto")
    if backend == "numba" and device.type != "cpu":
        raise ConfigError(f"synth.backend=numba runs on the CPU only; this run uses device {device} "
                          "(use synth.backend=auto or device=cpu)")
    return backend != "torch" and AVAILABLE and device.type == "cpu"


_JIT = dict(cache=True, nogil=True, error_model="numpy", boundscheck=False)


@njit(inline="always", **_JIT)
def _set_key(picks: np.ndarray, valid: np.ndarray, codes: np.ndarray) -> np.int64:
    """(K,) picks and their dedup flags -> name of the picked set (1 + sum of member codes)."""
    key = np.int64(1)
    for k in range(picks.shape[0]):
        if valid[k]:
            key += codes[picks[k]]
    return key


@njit(inline="always", **_JIT)
def _dedup(picks: np.ndarray, valid: np.ndarray) -> None:
    """valid[k] = picks[k] >= 0 and no earlier rule picked the same agent (as ``dedup_valid``)."""
    for k in range(picks.shape[0]):
        ok = picks[k] >= 0
        for m in range(k):
            if picks[m] == picks[k]:
                ok = False
        valid[k] = ok


def incremental_rows(new_cols: np.ndarray, changed: np.ndarray, *, table: np.ndarray, n: int, codes: np.ndarray,
                     memo_key: np.ndarray, memo_l1: np.ndarray, l1: np.ndarray, deg_in: np.ndarray,
                     deg_out: np.ndarray, todo_rows: np.ndarray, todo_picks: np.ndarray, todo_valid: np.ndarray,
                     todo_keys: np.ndarray) -> tuple[int, int]:
    """Apply the changed rules' new picks to one bucket, in place on copies of the accepted state.

    new_cols (C, R) int8 or int16: the new picks of the changed rules; changed (C,) int64: their positions in the table.
    table (R, K) (as new_cols), l1 (R,) float32, deg_in/deg_out (R,) int32: updated in place (callers pass copies).
    n: agents per state; codes (N,) int64: each agent's random code (a set's name is 1 + the sum of its members').
    memo_key (R, MEMO) int64, memo_l1 (R, MEMO) float32: the memo (no rows before the last round).
    An agent whose picked set is unchanged keeps its L1; one whose new set is in the memo (one slot per set name,
    ``key % MEMO``) takes the remembered L1; the others are listed in todo_* (rows, (M, K) picks, valid, keys)
    for the forward pass. Returns (M, memo hits)."""
    return _incremental_rows(new_cols, changed, table, n, codes, memo_key, memo_l1, l1, deg_in, deg_out,
                             todo_rows, todo_picks, todo_valid, todo_keys)


@njit(**_JIT)
def _incremental_rows(new_cols, changed, table, n, codes, memo_key, memo_l1, l1, deg_in, deg_out,
                      todo_rows, todo_picks, todo_valid, todo_keys):
    """``incremental_rows``, compiled (numba takes its arguments by position)."""
    r_total, k_rules = table.shape
    n_memo = memo_key.shape[1]
    use_memo = memo_key.shape[0] > 0
    old = np.empty(k_rules, np.int64)
    new = np.empty(k_rules, np.int64)
    old_valid = np.empty(k_rules, np.bool_)
    new_valid = np.empty(k_rules, np.bool_)
    m = 0
    hits = 0
    for r in range(r_total):
        diff = False
        for c in range(changed.shape[0]):
            if new_cols[c, r] != table[r, changed[c]]:
                diff = True
        if not diff:
            continue
        for k in range(k_rules):
            old[k] = table[r, k]
            new[k] = table[r, k]
        for c in range(changed.shape[0]):
            new[changed[c]] = new_cols[c, r]
            table[r, changed[c]] = new_cols[c, r]
        _dedup(old, old_valid)
        _dedup(new, new_valid)
        # degree counts: the old picks lose this listener, the new picks gain it (paper section 3.4's degree)
        base = r - r % n
        cnt = 0
        for k in range(k_rules):
            if old_valid[k]:
                deg_out[base + old[k]] -= 1
            if new_valid[k]:
                deg_out[base + new[k]] += 1
                cnt += 1
        deg_in[r] = cnt
        key = _set_key(new, new_valid, codes)
        if key == _set_key(old, old_valid, codes):
            continue  # another rule already picked the new agent: the same set, the same action
        if use_memo:
            slot = key % n_memo
            if memo_key[r, slot] == key:
                l1[r] = memo_l1[r, slot]
                hits += 1
                continue
        todo_rows[m] = r
        for k in range(k_rules):
            todo_picks[m, k] = new[k]
            todo_valid[m, k] = new_valid[k]
        todo_keys[m] = key
        m += 1
    return m, hits


@njit(**_JIT)
def store_rows(rows, keys, fresh, l1, memo_key, memo_l1):
    """Write the freshly computed L1 of rows (M,) into l1 (R,) and the memo."""
    n_memo = memo_key.shape[1]
    use_memo = memo_key.shape[0] > 0
    for m in range(rows.shape[0]):
        r = rows[m]
        l1[r] = fresh[m]
        if use_memo:
            slot = keys[m] % n_memo
            memo_key[r, slot] = keys[m]
            memo_l1[r, slot] = fresh[m]


@njit(**_JIT)
def degree_sum(deg_in, deg_out, n, hinge, cap):
    """(R,) in/out degrees -> sum over states of the degree term (max_i in + out, or the reference's hinges)."""
    total = 0.0
    for s in range(deg_in.shape[0] // n):
        best = 0
        best_in = 0
        best_out = 0
        for i in range(s * n, s * n + n):
            best = max(best, deg_in[i] + deg_out[i])
            best_in = max(best_in, deg_in[i])
            best_out = max(best_out, deg_out[i])
        if hinge:
            total += max(best_in - cap, 0) + max(best_out - cap, 0)
        else:
            total += best
    return total


# ------------------------------------------------------------------------------------------ rule scans
# A filter is compiled to at most two tests joined by ``op`` (0: true, 1: one test, 2: and, 3: or); each test is
# a linear form of up to T terms over the stacked features: ids < P index the pair features fp (P, R N), ids >= P
# the agent features fa (A, R). The score's candidate order (or the uniforms' order of a random rule) is
# precomputed per agent, so an agent's pick is the first candidate in that order that its filter passes.
@njit(inline="always", **_JIT)
def _test_value(fp, fa, n_pair, r, rj, feat, w, nterm, t):
    """Value of test t's linear form for row r and flat pair index rj = r N + j, in float32 as torch sums it
    (2-D indexing, no row slices: a slice inside the scan loop costs more than the test)."""
    acc = np.float32(0.0)
    for m in range(nterm[t]):
        f = feat[t, m]
        v = fp[f, rj] if f < n_pair else fa[f - n_pair, r]
        acc = v * w[t, m] if m == 0 else acc + v * w[t, m]
    return acc


def scan_picks(spec: RuleSpec, *, pair_feats: np.ndarray, agent_feats: np.ndarray, n: int,
               order: np.ndarray | None, out: np.ndarray) -> None:
    """out (R,) int8 or int16: each row's pick under the rule ``spec``, -1 when its filter passes nobody.

    pair_feats (P, R N) and agent_feats (A, R): the stacked features (``Prepared.scan_inputs``); n: agents per
    state. order (R, N) (as out): each row's candidates best first (ties: lower index first, as torch's max); None
    for a rule whose score is the same for every candidate (``spec.order`` None: index order 0..N-1)."""
    natural = spec.order is None
    if natural:
        order = np.zeros((1, 1), out.dtype)  # unused, but numba wants an array of the picks' type
    _scan_picks(pair_feats, agent_feats, n, spec.op, spec.feat, spec.w, spec.nterm, spec.thr, spec.agent_level,
                order, natural, out)


@njit(**_JIT)
def _scan_picks(fp, fa, n, op, feat, w, nterm, thr, agent_level, order, natural, out):
    """``scan_picks``, compiled. op: filter shape (above); feat (2, T) int64, w (2, T) float32, nterm (2,),
    thr (2,) float32, agent_level (2,) bool: the tests; natural: ignore ``order`` and use 0..N-1."""
    n_pair = fp.shape[0]
    r_total = out.shape[0]
    # the common test, one pair feature times a weight, read through a hoisted 1-D view (no term loop)
    one0 = nterm[0] == 1 and feat[0, 0] < n_pair
    one1 = nterm[1] == 1 and feat[1, 0] < n_pair
    p0 = fp[feat[0, 0] if one0 else 0]
    p1 = fp[feat[1, 0] if one1 else 0]
    w0 = w[0, 0]
    w1 = w[1, 0]
    for r in range(r_total):
        i = r % n
        # tests of agent i alone pass every candidate or none: decide them once per row (1 true, -1 false,
        # 0 depends on the candidate)
        c0 = 0
        c1 = 0
        if op != 0 and agent_level[0]:
            c0 = 1 if _test_value(fp, fa, n_pair, r, r * n, feat, w, nterm, 0) >= thr[0] else -1
        if op >= 2 and agent_level[1]:
            c1 = 1 if _test_value(fp, fa, n_pair, r, r * n, feat, w, nterm, 1) >= thr[1] else -1
        if op == 1:
            decided = c0
        elif op == 2:
            decided = -1 if (c0 == -1 or c1 == -1) else (1 if c0 == 1 and c1 == 1 else 0)
        elif op == 3:
            decided = 1 if (c0 == 1 or c1 == 1) else (-1 if c0 == -1 and c1 == -1 else 0)
        else:
            decided = 1
        pick = -1
        if decided != -1:
            for q in range(n):
                j = q if natural else order[r, q]
                if j == i:
                    continue
                if decided == 1:
                    pick = j
                    break
                rj = r * n + j
                # the two tests are written out: the same logic as one inlined helper made this loop 10x slower
                # (numba 0.68: 65 -> 700 ns per agent for a filter that passes nobody)
                if c0 != 0:
                    ok0 = c0 == 1
                elif one0:
                    ok0 = p0[rj] * w0 >= thr[0]
                else:
                    ok0 = _test_value(fp, fa, n_pair, r, rj, feat, w, nterm, 0) >= thr[0]
                if op >= 2:
                    if c1 != 0:
                        ok1 = c1 == 1
                    elif one1:
                        ok1 = p1[rj] * w1 >= thr[1]
                    else:
                        ok1 = _test_value(fp, fa, n_pair, r, rj, feat, w, nterm, 1) >= thr[1]
                if op == 1:
                    ok = ok0
                elif op == 2:
                    ok = ok0 and ok1
                else:
                    ok = ok0 or ok1
                if ok:
                    pick = j
                    break
        out[r] = pick


@dataclass(frozen=True)
class RuleSpec:
    """A rule in the form ``scan_picks`` reads; ``order`` names the candidate order: ("score", feature, sign)
    for an argmax over one pair feature, ("random",) for a random rule, None for index order (a score that is
    the same for every candidate)."""

    op: int
    feat: np.ndarray  # (2, T) int64
    w: np.ndarray  # (2, T) float32
    nterm: np.ndarray  # (2,) int64
    thr: np.ndarray  # (2,) float32
    agent_level: np.ndarray  # (2,) bool
    order: tuple | None


def rule_spec(rule: Rule, pair: list[str], agent: list[str]) -> RuleSpec | None:
    """Compile a rule over the named pair and agent features; None when ``scan_picks`` does not cover it (deeper
    filters, or an argmax over a sum of pair features: those stay with the torch evaluator)."""
    ids = {nm: k for k, nm in enumerate(pair)} | {nm: len(pair) + k for k, nm in enumerate(agent)}
    if not rule_features(rule) <= ids.keys():
        return None  # the torch evaluator names the unknown feature
    c = rule.cond
    if isinstance(c, TrueCond):
        op, tests = 0, []
    elif isinstance(c, Test):
        op, tests = 1, [c]
    elif isinstance(c, (And, Or)) and isinstance(c.left, Test) and isinstance(c.right, Test):
        op, tests = (2 if isinstance(c, And) else 3), [c.left, c.right]
    else:
        return None
    t_max = max([len(t.lhs.terms) for t in tests] + [1])
    feat = np.zeros((2, t_max), np.int64)
    w = np.zeros((2, t_max), np.float32)
    nterm = np.zeros(2, np.int64)
    thr = np.zeros(2, np.float32)  # torch compares a float32 tensor with the threshold cast to float32
    agent_level = np.ones(2, np.bool_)
    for k, t in enumerate(tests):
        for m, (name, wt) in enumerate(t.lhs.terms):
            feat[k, m], w[k, m] = ids[name], wt
        nterm[k] = len(t.lhs.terms)
        thr[k] = t.threshold
        agent_level[k] = all(name in agent for name, _ in t.lhs.terms)
    if isinstance(rule, RandomRule):
        order: tuple | None = ("random",)
    elif all(name in agent for name, _ in rule.score.terms):
        order = None  # every candidate ties; torch's max takes the lowest index
    elif len(rule.score.terms) == 1 and abs(rule.score.terms[0][1]) == 1.0:
        name, wt = rule.score.terms[0]
        order = ("score", name, wt > 0)
    else:
        return None
    return RuleSpec(op, feat, w, nterm, thr, agent_level, order)
