"""Compiled CPU kernel of a program's whole filter scan on the sparse path (numba): per pair (i, j), the noisy offset
o_ij, the pair features the program reads, every rule's filter and score, and a running best per rule, in one pass
with no (R, N) temporaries (policy/scan.py compiles the program into the arrays read here).

It computes the numbers of the torch scan (``scan_program``'s reference path: tasks/pairs.py ``Offsets.rows``,
tasks/features.py, dsl/interpret.py ``rule_picks``) in the same float32 operations and order: the norm as torch's
vectorised reduction does it (x x, then a fused multiply-add of y y: emulated in float64, where the product is
exact; the double rounding differs from one fused rounding in about 1 of 2^29 sums), atan2 of float32, each linear
form summed term by term, thresholds compared in float32, ties to the lower index (torch's ``max``).
tests/test_pairs.py compares the picks with the torch scan's.

Shapes: N agents of one episode, R receivers first..first+R-1, K rules, P pair features, A agent features, T terms
of a linear form, M tests of a filter, L postfix codes of a filter.
"""

from __future__ import annotations

import math

import numpy as np

from ..tasks.pair_kernels import _JIT, AVAILABLE, _bits, njit

__all__ = ["AVAILABLE", "program_scan", "X", "Y", "D", "THETA", "PRODUCT", "THETA_EXACT", "TRUE", "TEST", "AND", "OR"]

X, Y, D, THETA, PRODUCT, THETA_EXACT = 0, 1, 2, 3, 4, 5
"""pair feature kinds: a part of sign * o_ij, or the product of two features (ids in the feature space below);
THETA is the fast angle, refined where a decision is close, THETA_EXACT atan2f for every pair (an angle that is a
factor of a product)"""
TRUE, TEST, AND, OR = 0, 1, 2, 3
"""filter codes, postfix: push true; push test ``arg`` >= its threshold; pop two, push their and / or"""


@njit(inline="always", **_JIT)
def _norm(x: np.float32, y: np.float32) -> np.float32:
    """torch's float32 norm of (x, y): fma(y, y, x x) rounded once, then sqrt (both products are exact in float64)."""
    xx = np.float64(np.float32(x * x))
    return np.float32(math.sqrt(np.float32(np.float64(y) * np.float64(y) + xx)))


THETA_ERR = np.float32(1e-5)
"""rad: a bound on |_atan2_fast(y, x) - atan2f(y, x)| (measured: under 1e-6 on 10^7 pairs, tests/test_pairs.py);
the scan decides a comparison by the fast angle when it is farther than this from the threshold or the best score,
and computes atan2 exactly otherwise, so the picks are the exact ones"""

_PI = np.float32(math.pi)
_PI_2 = np.float32(math.pi / 2)
_PI_4 = np.float32(math.pi / 4)
_TAN_PI_8 = np.float32(0.4142135623730950)


@njit(inline="always", **_JIT)
def _atan2_fast(y: np.float32, x: np.float32) -> np.float32:
    """atan2 in float32 within THETA_ERR, without branches (the compiler vectorises it): octant reduction to
    [0, 1], cephes' atanf (a second reduction at tan(pi/8) and a degree-9 odd polynomial), signs restored from the
    sign bits (so atan2(-0, -1) = -pi as atan2f gives)."""
    ax = abs(x)
    ay = abs(y)
    mx = max(ax, ay)
    mn = min(ax, ay)
    a = mn / mx if mx > 0 else np.float32(0.0)
    big = a > _TAN_PI_8
    t = (a - np.float32(1.0)) / (a + np.float32(1.0)) if big else a
    z = t * t
    p = (((np.float32(8.05374449538e-2) * z - np.float32(1.38776856032e-1)) * z + np.float32(1.99777106478e-1)) * z
         - np.float32(3.33329491539e-1)) * z * t + t
    r = p + _PI_4 if big else p
    r = _PI_2 - r if ay > ax else r
    r = _PI - r if math.copysign(1.0, x) < 0 else r
    return np.float32(math.copysign(r, y))


@njit(inline="always", **_JIT)
def _linear_row(frow, fa, n_pair, perr, i, ids, w, nterm, acc, mag):
    """acc (N,) float32 <- sum_t w_t phi_t for receiver i and every candidate, term by term as dsl/interpret.py
    ``linear`` adds them (0 for no terms); ids < P read the pair feature rows frow (P, N), ids >= P the agent
    features fa (A, N) of agent i. Returns the bound sum_t |w_t| perr_t on the error of the fast angles;
    where it is not 0, mag (N,) <- sum_t |w_t phi_t|, which bounds the rounding of the sum (``_margin``)."""
    n = acc.shape[0]
    bound = np.float32(0.0)
    for t in range(nterm):
        f = ids[t]
        if f < n_pair:
            bound += abs(w[t]) * perr[f]
    if nterm == 0:
        acc[:] = np.float32(0.0)
    for t in range(nterm):
        f = ids[t]
        wt = w[t]
        if f < n_pair:
            if t == 0:
                for j in range(n):
                    acc[j] = frow[f, j] * wt
            else:
                for j in range(n):
                    acc[j] = acc[j] + frow[f, j] * wt
        else:
            v = np.float32(fa[f - n_pair, i] * wt)
            if t == 0:
                acc[:] = v
            else:
                for j in range(n):
                    acc[j] = acc[j] + v
    if bound > 0:
        mag[:] = np.float32(0.0)
        for t in range(nterm):
            f = ids[t]
            wt = w[t]
            if f < n_pair:
                for j in range(n):
                    mag[j] += abs(frow[f, j] * wt)
            else:
                v = abs(fa[f - n_pair, i] * wt)
                for j in range(n):
                    mag[j] += v
    return bound


@njit(inline="always", **_JIT)
def _margin(bound, mag):
    """How far a fast linear value can be from the exact one: twice the angles' bound, and 2^-19 of the terms'
    magnitudes for the roundings of up to 8 products and sums that may round the other way."""
    return np.float32(2.0) * bound + np.float32(1.0 / (1 << 19)) * mag


@njit(inline="always", **_JIT)
def _exact(frow, fa, n_pair, pk, psign, ox, oy, i, j, ids, w, nterm):
    """The linear form of candidate j with every angle computed by atan2f: the value torch's scan computes."""
    acc = np.float32(0.0)
    for t in range(nterm):
        f = ids[t]
        if f >= n_pair:
            v = fa[f - n_pair, i]
        elif pk[f] == THETA:
            s = np.float32(-1.0) if psign[f] < 0 else np.float32(1.0)
            v = np.float32(math.atan2(oy[j] * s, ox[j] * s))
        else:
            v = frow[f, j]
        term = np.float32(v * w[t])
        acc = term if t == 0 else np.float32(acc + term)
    return acc


@njit(**_JIT)
def program_scan(pos, lo, hi, sigma, radius, cossin, first, fa,
                 pk, psign, pa, pb,
                 kind, klo, khi, sf, sw, sn,
                 code, arg, clen, tf, tw, tn, thr,
                 out):
    """out (R, K) int64 <- each rule's pick for receivers first..first+R-1 of one episode, -1 when its filter passes
    nobody. One receiver at a time: its row of offsets, features, tests and scores lives in buffers of N values
    (level-1 cache), each a loop the compiler vectorises; angles are the fast ones, and a test or a best score
    whose fast value is within ``_margin`` of deciding otherwise is computed again with atan2f.

    pos (N, 2) float32; lo, hi: the observation key's 31-bit halves; sigma: the noise std (0: none); radius (65536,),
    cossin (65536, 2) float32: the Box-Muller tables (cos and sin side by side: one cache line per look-up); fa (A, N)
    float32: the agent features of every agent.
    Pair features (P,): pk kind, psign +1/-1 (the vector's sign), pa, pb the factors' ids of a PRODUCT (ids < P:
    pair features, computed before it; ids >= P: agent features).
    Rules (K,): kind 0 argmax / 1 random, klo, khi the random rule's key halves, sf (K, T) ids, sw (K, T) float32
    weights, sn (K,) terms of the score; code, arg (K, L) the filter in postfix, clen (K,) its length; tf (K, M, T),
    tw (K, M, T), tn (K, M), thr (K, M) float32 the tests."""
    n = pos.shape[0]
    n_pair = pk.shape[0]
    k_rules = kind.shape[0]
    ox = np.empty(n, np.float32)
    oy = np.empty(n, np.float32)
    frow = np.empty((max(n_pair, 1), n), np.float32)
    perr = np.zeros(max(n_pair, 1), np.float32)
    for p in range(n_pair):
        if pk[p] == THETA:
            perr[p] = THETA_ERR
    acc = np.empty(n, np.float32)
    mag = np.empty(n, np.float32)
    stack = np.empty((max(code.shape[1], 1), n), np.bool_)
    inv24 = np.float32(1.0 / (1 << 24))
    for r in range(out.shape[0]):
        i = first + r
        xi, yi = pos[i, 0], pos[i, 1]
        for j in range(n):
            ox[j] = pos[j, 0] - xi
            oy[j] = pos[j, 1] - yi
        if sigma > 0:  # tasks/pair_kernels.py noisy_rows: the same hash of (key, i N + j)
            for j in range(n):
                h = _bits(i * n + j, lo, hi)
                rad = radius[h >> np.uint32(16)]
                q = h & np.uint32(0xFFFF)
                ox[j] = ox[j] + sigma * (rad * cossin[q, 0])
                oy[j] = oy[j] + sigma * (rad * cossin[q, 1])
        for p in range(n_pair):
            c = pk[p]
            s = np.float32(-1.0) if psign[p] < 0 else np.float32(1.0)  # x (-1) is exact negation
            if c == X:
                for j in range(n):
                    frow[p, j] = ox[j] * s
            elif c == Y:
                for j in range(n):
                    frow[p, j] = oy[j] * s
            elif c == D:
                for j in range(n):
                    frow[p, j] = _norm(ox[j], oy[j])  # the norm of -o is the norm of o
            elif c == THETA:
                for j in range(n):
                    frow[p, j] = _atan2_fast(oy[j] * s, ox[j] * s)
            elif c == THETA_EXACT:
                for j in range(n):
                    frow[p, j] = math.atan2(oy[j] * s, ox[j] * s)
            else:
                a, b = pa[p], pb[p]
                if a < n_pair and b < n_pair:
                    for j in range(n):
                        frow[p, j] = frow[a, j] * frow[b, j]
                elif a < n_pair or b < n_pair:
                    row = a if a < n_pair else b
                    v = fa[(b if a < n_pair else a) - n_pair, i]
                    for j in range(n):
                        frow[p, j] = frow[row, j] * v
                else:
                    frow[p, :] = fa[a - n_pair, i] * fa[b - n_pair, i]
        for k in range(k_rules):
            top = 0
            for s_ in range(clen[k]):
                op = code[k, s_]
                if op == TRUE:
                    stack[top, :] = True
                    top += 1
                elif op == TEST:
                    t = arg[k, s_]
                    bound = _linear_row(frow, fa, n_pair, perr, i, tf[k, t], tw[k, t], tn[k, t], acc, mag)
                    th = thr[k, t]
                    for j in range(n):
                        stack[top, j] = acc[j] >= th
                    if bound > 0:  # close calls by the exact angle
                        for j in range(n):
                            if abs(acc[j] - th) <= _margin(bound, mag[j]):
                                stack[top, j] = _exact(frow, fa, n_pair, pk, psign, ox, oy, i, j, tf[k, t], tw[k, t],
                                                       tn[k, t]) >= th
                    top += 1
                elif op == AND:
                    top -= 1
                    for j in range(n):
                        stack[top - 1, j] = stack[top - 1, j] and stack[top, j]
                else:
                    top -= 1
                    for j in range(n):
                        stack[top - 1, j] = stack[top - 1, j] or stack[top, j]
            stack[0, i] = False  # nobody asks itself
            pick = -1
            best = np.float32(0.0)
            if kind[k] == 0:
                bound = _linear_row(frow, fa, n_pair, perr, i, sf[k], sw[k], sn[k], acc, mag)
                for j in range(n):
                    if stack[0, j] and (pick < 0 or acc[j] > best):  # strictly greater: ties to the lower index
                        best = acc[j]
                        pick = j
                if bound > 0 and pick >= 0:  # every candidate the fast scores cannot tell from the best, exactly
                    floor = best - _margin(bound, mag[pick])
                    pick = -1
                    for j in range(n):
                        if stack[0, j] and acc[j] + _margin(bound, mag[j]) >= floor:
                            v = _exact(frow, fa, n_pair, pk, psign, ox, oy, i, j, sf[k], sw[k], sn[k])
                            if pick < 0 or v > best:
                                best = v
                                pick = j
            else:  # tasks/pairs.py counter_uniform of the rule's key and i N + j (every j: a loop without branches)
                for j in range(n):
                    h = _bits(i * n + j, klo[k], khi[k])
                    acc[j] = (np.float32((h >> np.uint32(8)) & np.uint32(0xFFFFFF)) + np.float32(0.5)) * inv24
                for j in range(n):
                    if stack[0, j] and (pick < 0 or acc[j] > best):
                        best = acc[j]
                        pick = j
            out[r, k] = pick
