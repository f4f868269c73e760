"""The program's filter scan by cells (numba): bounds per block of pairs decide most of it, so a receiver's work is
its random rules' hashes (one per candidate, vectorised) and the few pairs near a decision, not every noisy pair.

The agents of an episode are sorted into the cells of a grid. For receiver i and cell c, the noisy offsets o_ij of
c's agents lie in a rectangle: the cell's members' bounding box minus i's position, widened by the noise's bound
(sigma times the largest radius of the Box-Muller table) and by a float32 rounding allowance. Every pair feature
the kernel knows (x, y, d, theta, products) gets an interval from it, and so does every linear form, so a filter is
true, false or undecided for the whole cell (three-valued: and = min, or = max):

* an **argmax rule** visits cells by decreasing upper bound of its score and stops when the next bound is below the
  best score found: only the members of the visited cells are computed (their noise, features, filter, score);
* a **random rule** takes the largest counter uniform over all candidates (one hash each, as the reference draws
  them; a 64-bit key, ``uniform_key``, makes the uniform, then the lower index, decide in one vectorised max),
  then asks whether the winner passes the filter: its cell's bounds say so, or the pair is computed; a loser is
  struck out and the max taken again (after ``RETRIES`` losers, every cell's bounds are read and only the
  undecided members computed).

A computed pair is the fused kernel's (policy/scan_kernels.py): the same float32 operations, the fast angle with
its close calls decided by atan2f, so the picks are bit for bit the reference scan's (tests/test_scan.py). Shapes:
N agents of one episode, R receivers, C non-empty cells, P pair features, K rules.
"""

from __future__ import annotations

import math

import numpy as np

from ..tasks.pair_kernels import _JIT, _bits, njit
from .scan_kernels import AND, D, PRODUCT, TEST, THETA, THETA_ERR, THETA_EXACT, TRUE, X, Y, _atan2_fast, _margin, \
    _norm

PER_CELL = 12
"""agents per cell the grid aims at: fewer makes tighter bounds and more cells to bound per receiver"""
RETRIES = 8
"""a random rule's struck-out winners before it reads every cell's bounds instead"""
_FALSE, _UNDECIDED, _TRUE = 0, 1, 2
_SLACK = 1e-5
"""relative allowance of the bounds for float32 rounding (a float32 operation rounds by 6e-8 of its magnitude)"""
_ANGLE_SLACK = 1e-4
"""rad: the angle bounds' allowance (the fast angle of a corner is within THETA_ERR of atan2, 1e-5)"""
_F32_MAX = 3.4028234663852886e38 / (1 + 2 * _SLACK)
"""a linear form whose terms may reach float32's largest value is not bounded (its float32 sum may be inf or NaN)"""


@njit(inline="always", **_JIT)
def uniform_key(h, j):
    """int64 > 0: a random rule's order of candidate j with counter hash h: larger for a larger float32 uniform
    (u24 + 0.5) 2^-24 (scan_kernels' value: above 2^23 the + 0.5 rounds to even, so neighbouring u24 can tie),
    then for a lower index (the reference's tie rule); 0 is left for a struck candidate."""
    u = np.float32(np.float32((h >> np.uint32(8)) & np.uint32(0xFFFFFF)) + np.float32(0.5))  # rounded as there
    return ((np.int64(u * np.float32(2.0)) + 1) << 32) | (0xFFFFFFFF - j)  # 2u is an integer below 2^25


@njit(**_JIT)
def _cells(pos, per_cell, cell_of, order, cstart, box):
    """Sort the N agents into the non-empty cells of a grid of about N / per_cell cells over their bounding box.
    Fills cell_of (N,) the cell of each agent, order (N,) the agents by cell, cstart (C + 1,) each cell's range in
    order, box (C, 4) float64 its members' x min, x max, y min, y max; returns C."""
    n = pos.shape[0]
    x0, x1, y0, y1 = np.inf, -np.inf, np.inf, -np.inf
    for j in range(n):
        x0, x1 = min(x0, np.float64(pos[j, 0])), max(x1, np.float64(pos[j, 0]))
        y0, y1 = min(y0, np.float64(pos[j, 1])), max(y1, np.float64(pos[j, 1]))
    w, h = max(x1 - x0, 1e-9), max(y1 - y0, 1e-9)
    size = math.sqrt(w * h * per_cell / n)
    nx = max(1, min(int(w / size) + 1, 4096))
    ny = max(1, min(int(h / size) + 1, 4096))
    grid = np.zeros(nx * ny + 1, np.int64)
    for j in range(n):
        cx = min(int((pos[j, 0] - x0) / w * nx), nx - 1)
        cy = min(int((pos[j, 1] - y0) / h * ny), ny - 1)
        cell_of[j] = cy * nx + cx
        grid[cell_of[j] + 1] += 1
    compact = np.full(nx * ny, -1, np.int64)
    c = 0
    for g in range(nx * ny):
        if grid[g + 1] > 0:
            compact[g] = c
            cstart[c + 1] = grid[g + 1]
            c += 1
    cstart[0] = 0
    for k in range(c):
        cstart[k + 1] += cstart[k]
    fill = cstart[:c].copy()
    for k in range(c):
        box[0, k], box[1, k], box[2, k], box[3, k] = np.inf, -np.inf, np.inf, -np.inf
    for j in range(n):
        k = compact[cell_of[j]]
        cell_of[j] = k
        order[fill[k]] = j
        fill[k] += 1
        box[0, k], box[1, k] = min(box[0, k], np.float64(pos[j, 0])), max(box[1, k], np.float64(pos[j, 0]))
        box[2, k], box[3, k] = min(box[2, k], np.float64(pos[j, 1])), max(box[3, k], np.float64(pos[j, 1]))
    return c


@njit(inline="always", **_JIT)
def _corner_angle(y, x):
    return np.float64(_atan2_fast(np.float32(y), np.float32(x)))


@njit(**_JIT)
def _bound_cells(c0, c1, want, box, xi, yi, reach, fa, i, pk, psign, pa, pb, flo, fhi):
    """flo, fhi (P, C) float64 columns c0..c1-1 <- for each pair feature p with want[p], an interval holding it for
    receiver i and any agent of that cell, as the scan computes it in float32 (reach: the noise's bound plus the
    rounding allowance, world units). One loop over the cells per feature (the compiler vectorises them)."""
    n_pair = pk.shape[0]
    for p in range(n_pair):
        if not want[p]:
            continue
        k = pk[p]
        neg = psign[p] < 0
        if k == X or k == Y:
            a0 = 0 if k == X else 2
            o = xi if k == X else yi
            if neg:
                for c in range(c0, c1):
                    flo[p, c] = o - box[a0 + 1, c] - reach
                    fhi[p, c] = o - box[a0, c] + reach
            else:
                for c in range(c0, c1):
                    flo[p, c] = box[a0, c] - o - reach
                    fhi[p, c] = box[a0 + 1, c] - o + reach
        elif k == D:
            for c in range(c0, c1):
                ax, bx = box[0, c] - xi - reach, box[1, c] - xi + reach
                ay, by = box[2, c] - yi - reach, box[3, c] - yi + reach
                gx = max(max(ax, -bx), 0.0)
                gy = max(max(ay, -by), 0.0)
                flo[p, c] = math.sqrt(gx * gx + gy * gy) * (1.0 - _SLACK)
                fhi[p, c] = math.sqrt(max(ax * ax, bx * bx) + max(ay * ay, by * by)) * (1.0 + _SLACK)
        elif k == THETA or k == THETA_EXACT:
            sg = -1.0 if neg else 1.0
            for c in range(c0, c1):  # the rectangle of sign o_ij
                x0, x1 = sg * (box[0, c] - xi), sg * (box[1, c] - xi)
                y0, y1 = sg * (box[2, c] - yi), sg * (box[3, c] - yi)
                lx, hx = min(x0, x1) - reach, max(x0, x1) + reach
                ly, hy = min(y0, y1) - reach, max(y0, y1) + reach
                a1, a2 = _corner_angle(ly, lx), _corner_angle(ly, hx)
                a3, a4 = _corner_angle(hy, lx), _corner_angle(hy, hx)
                # a convex set off the cut at +-pi has its angles between its corners'; with the origin or the cut
                # in reach, any angle
                anywhere = ly <= 0.0 <= hy and lx <= 0.0
                flo[p, c] = -math.pi - _ANGLE_SLACK if anywhere else min(min(a1, a2), min(a3, a4)) - _ANGLE_SLACK
                fhi[p, c] = math.pi + _ANGLE_SLACK if anywhere else max(max(a1, a2), max(a3, a4)) + _ANGLE_SLACK
        else:  # PRODUCT of two earlier pair features or agent features (ids >= P read agent i's)
            a, b = pa[p], pb[p]
            for c in range(c0, c1):
                alo = flo[a, c] if a < n_pair else np.float64(fa[a - n_pair, i])
                ahi = fhi[a, c] if a < n_pair else np.float64(fa[a - n_pair, i])
                blo = flo[b, c] if b < n_pair else np.float64(fa[b - n_pair, i])
                bhi = fhi[b, c] if b < n_pair else np.float64(fa[b - n_pair, i])
                p1, p2, p3, p4 = alo * blo, alo * bhi, ahi * blo, ahi * bhi
                lo_, hi_ = min(min(p1, p2), min(p3, p4)), max(max(p1, p2), max(p3, p4))
                big = _SLACK * max(abs(lo_), abs(hi_))
                flo[p, c] = lo_ - big
                fhi[p, c] = hi_ + big


@njit(inline="always", **_JIT)
def _linear_bounds(c, flo, fhi, fa, n_pair, i, ids, w, nterm):
    """(lo, hi) float64: an interval holding the linear form sum_t w_t phi_t over cell c, as float32 sums it."""
    lo = 0.0
    hi = 0.0
    mag = 0.0
    for t in range(nterm):
        f = ids[t]
        wt = np.float64(w[t])
        if f < n_pair:
            u, v = wt * flo[f, c], wt * fhi[f, c]
            lo += min(u, v)
            hi += max(u, v)
            mag += max(abs(u), abs(v))
        else:
            v = np.float64(np.float32(fa[f - n_pair, i] * w[t]))
            lo += v
            hi += v
            mag += abs(v)
    if mag >= _F32_MAX:  # a float32 term may overflow (inf - inf is NaN there): nothing is bounded
        return -np.inf, np.inf
    return lo - _SLACK * mag - 1e-30, hi + _SLACK * mag + 1e-30


@njit(**_JIT)
def _score_bounds(c0, c1, flo, fhi, fa, n_pair, i, ids, w, nterm, ub, mag):
    """ub (C,) entries c0..c1-1 <- an upper bound of the linear form over each cell (``_linear_bounds``' high end,
    term by term over the cells at once); mag (C,) scratch."""
    ub[c0:c1] = 0.0
    mag[c0:c1] = 0.0
    for t in range(nterm):
        f = ids[t]
        wt = np.float64(w[t])
        if f < n_pair:
            for c in range(c0, c1):
                u, v = wt * flo[f, c], wt * fhi[f, c]
                ub[c] += max(u, v)
                mag[c] += max(abs(u), abs(v))
        else:
            v = np.float64(np.float32(fa[f - n_pair, i] * w[t]))
            for c in range(c0, c1):
                ub[c] += v
                mag[c] += abs(v)
    for c in range(c0, c1):
        ub[c] = np.inf if mag[c] >= _F32_MAX else ub[c] + _SLACK * mag[c] + 1e-30


@njit(inline="always", **_JIT)
def _cell_filter(c, k, flo, fhi, fa, n_pair, i, code, arg, clen, tf, tw, tn, thr, stack):
    """Rule k's filter over every pair of receiver i and cell c: _FALSE, _TRUE or _UNDECIDED (Kleene logic)."""
    top = 0
    for s_ in range(clen[k]):
        op = code[k, s_]
        if op == TRUE:
            stack[top] = _TRUE
            top += 1
        elif op == TEST:
            t = arg[k, s_]
            lo, hi = _linear_bounds(c, flo, fhi, fa, n_pair, i, tf[k, t], tw[k, t], tn[k, t])
            th = np.float64(thr[k, t])
            stack[top] = _TRUE if lo >= th else (_FALSE if hi < th else _UNDECIDED)
            top += 1
        elif op == AND:
            top -= 1
            stack[top - 1] = min(stack[top - 1], stack[top])
        else:
            top -= 1
            stack[top - 1] = max(stack[top - 1], stack[top])
    return stack[0]


@njit(**_JIT)
def _offsets(pos, lo, hi, sigma, radius, cossin, i, order, s0, s1, mox, moy):
    """mox, moy (s1 - s0,) float32 <- the noisy offsets o_ij of receiver i and agents j = order[s0:s1] as
    scan_kernels computes them (tasks/pair_kernels.py noisy_rows), in one loop the compiler vectorises (about 6x
    the speed of a scalar call per pair)."""
    n = pos.shape[0]
    xi, yi = pos[i, 0], pos[i, 1]
    base = i * n
    if sigma > 0:
        for s_ in range(s0, s1):
            j = order[s_]
            h = _bits(base + j, lo, hi)
            rad = radius[h >> np.uint32(16)]
            q = h & np.uint32(0xFFFF)
            mox[s_ - s0] = (pos[j, 0] - xi) + sigma * (rad * cossin[q, 0])
            moy[s_ - s0] = (pos[j, 1] - yi) + sigma * (rad * cossin[q, 1])
    else:
        for s_ in range(s0, s1):
            j = order[s_]
            mox[s_ - s0] = pos[j, 0] - xi
            moy[s_ - s0] = pos[j, 1] - yi


@njit(inline="always", **_JIT)
def _features(ox, oy, fa, i, pk, psign, pa, pb, fj, which, value):
    """fj (P,) float32 <- the features p with which[p] == value of a pair with noisy offset (ox, oy), as the fused
    kernel computes them (the fast angle for THETA)."""
    n_pair = pk.shape[0]
    for p in range(n_pair):
        if which[p] != value:
            continue
        k = pk[p]
        s = np.float32(-1.0) if psign[p] < 0 else np.float32(1.0)
        if k == X:
            fj[p] = ox * s
        elif k == Y:
            fj[p] = oy * s
        elif k == D:
            fj[p] = _norm(ox, oy)
        elif k == THETA:
            fj[p] = _atan2_fast(oy * s, ox * s)
        elif k == THETA_EXACT:
            fj[p] = math.atan2(oy * s, ox * s)
        else:
            a, b = pa[p], pb[p]
            va = fj[a] if a < n_pair else fa[a - n_pair, i]
            vb = fj[b] if b < n_pair else fa[b - n_pair, i]
            if a < n_pair and b < n_pair:
                fj[p] = va * vb
            elif a < n_pair:
                fj[p] = fj[a] * vb
            elif b < n_pair:
                fj[p] = fj[b] * va
            else:
                fj[p] = fa[a - n_pair, i] * fa[b - n_pair, i]


@njit(inline="always", **_JIT)
def _form(fj, fa, n_pair, pk, psign, ox, oy, i, ids, w, nterm, exact):
    """(value, margin) float32: the linear form of one pair, term by term as scan_kernels' ``_linear_row`` adds
    them; with exact, every angle by atan2f and margin 0, else the fast angles and how far the value may be from
    the exact one (scan_kernels ``_margin``)."""
    acc = np.float32(0.0)
    bound = np.float32(0.0)
    mag = np.float32(0.0)
    for t in range(nterm):
        f = ids[t]
        wt = w[t]
        if f >= n_pair:
            term = np.float32(fa[f - n_pair, i] * wt)
        else:
            v = fj[f]
            if pk[f] == THETA:
                if exact:
                    s = np.float32(-1.0) if psign[f] < 0 else np.float32(1.0)
                    v = np.float32(math.atan2(oy * s, ox * s))
                else:
                    bound += abs(wt) * THETA_ERR
            term = np.float32(v * wt)
        mag += abs(term)
        acc = term if t == 0 else np.float32(acc + term)
    return acc, (_margin(bound, mag) if bound > 0 else np.float32(0.0))


@njit(inline="always", **_JIT)
def _pair_filter(fj, fa, n_pair, pk, psign, ox, oy, i, k, code, arg, clen, tf, tw, tn, thr, stack):
    """Rule k's filter on one computed pair, exact (a test within its margin is done again by atan2f)."""
    top = 0
    for s_ in range(clen[k]):
        op = code[k, s_]
        if op == TRUE:
            stack[top] = 1
            top += 1
        elif op == TEST:
            t = arg[k, s_]
            th = thr[k, t]
            v, m = _form(fj, fa, n_pair, pk, psign, ox, oy, i, tf[k, t], tw[k, t], tn[k, t], False)
            if m > 0 and abs(v - th) <= m:
                v, m = _form(fj, fa, n_pair, pk, psign, ox, oy, i, tf[k, t], tw[k, t], tn[k, t], True)
            stack[top] = 1 if v >= th else 0
            top += 1
        elif op == AND:
            top -= 1
            stack[top - 1] = min(stack[top - 1], stack[top])
        else:
            top -= 1
            stack[top - 1] = max(stack[top - 1], stack[top])
    return stack[0] == 1


@njit(**_JIT)
def cell_scan(pos, lo, hi, sigma, radius, cossin, first, fa,
              pk, psign, pa, pb,
              kind, klo, khi, sf, sw, sn,
              code, arg, clen, tf, tw, tn, thr,
              out, reach):
    """out (R, K) int64 <- each rule's pick for receivers first..first+R-1 of one episode (-1: its filter passes
    nobody), the picks of ``scan_kernels.program_scan`` (same arguments, its docstring has them), decided by cells.
    reach: the noise's bound on |o_ij - (p_j - p_i)| per axis plus the rounding allowance, world units."""
    n = pos.shape[0]
    n_pair = pk.shape[0]
    k_rules = kind.shape[0]
    cell_of = np.empty(n, np.int64)
    order = np.empty(n, np.int64)
    cstart = np.zeros(n + 1, np.int64)
    box = np.empty((4, n), np.float64)
    cells = _cells(pos, PER_CELL, cell_of, order, cstart, box)
    slot = np.empty(n, np.int64)  # each agent's place in order
    for s_ in range(n):
        slot[order[s_]] = s_
    pw = max(n_pair, 1)
    flo = np.empty((pw, cells), np.float64)
    fhi = np.empty((pw, cells), np.float64)
    every = np.ones(pw, np.bool_)
    need = np.zeros((k_rules, pw), np.bool_)  # the pair features an argmax rule's score reads, factors included
    for k in range(k_rules):
        for t in range(sn[k]):
            if sf[k, t] < n_pair:
                need[k, sf[k, t]] = True
        for p in range(n_pair - 1, -1, -1):
            if need[k, p] and pk[p] == PRODUCT:
                for f in (pa[p], pb[p]):
                    if f < n_pair:
                        need[k, f] = True
    whole = np.zeros(pw, np.bool_)  # features bounded over every cell for this receiver
    want = np.zeros(pw, np.bool_)
    done = np.full(cells, -1, np.int64)  # the receiver whose every feature cell c holds
    state = np.empty(cells, np.int64)
    seen = np.full(cells, -1, np.int64)  # the (receiver, rule) whose state cell c holds
    ub = np.empty(cells, np.float64)
    mag = np.empty(cells, np.float64)
    mox = np.empty(n, np.float32)  # a visited cell's members' noisy offsets
    moy = np.empty(n, np.float32)
    fj = np.empty(pw, np.float32)
    key = np.empty(n, np.int64)
    stack = np.empty(max(code.shape[1], 1), np.int64)
    for r in range(out.shape[0]):
        i = first + r
        xi, yi = np.float64(pos[i, 0]), np.float64(pos[i, 1])
        whole[:] = False
        for k in range(k_rules):
            tag = i * k_rules + k
            pick = -1
            if kind[k] == 0:  # argmax: cells by decreasing bound of the score, until none can beat the best
                any_ = False
                for p in range(n_pair):
                    want[p] = need[k, p] and not whole[p]
                    any_ = any_ or want[p]
                    whole[p] = whole[p] or need[k, p]
                if any_:
                    _bound_cells(0, cells, want, box, xi, yi, reach, fa, i, pk, psign, pa, pb, flo, fhi)
                _score_bounds(0, cells, flo, fhi, fa, n_pair, i, sf[k], sw[k], sn[k], ub, mag)
                best = np.float32(0.0)
                while True:
                    c = -1
                    top = -np.inf
                    for g in range(cells):
                        if ub[g] > top:
                            top = ub[g]
                            c = g
                    if c < 0 or (pick >= 0 and top < best):
                        break
                    ub[c] = -np.inf
                    if done[c] != i:
                        _bound_cells(c, c + 1, every, box, xi, yi, reach, fa, i, pk, psign, pa, pb, flo, fhi)
                        done[c] = i
                    st = _cell_filter(c, k, flo, fhi, fa, n_pair, i, code, arg, clen, tf, tw, tn, thr, stack)
                    if st == _FALSE:
                        continue
                    # every member's noisy offset first, in a loop without branches (its look-ups overlap)
                    s0, s1 = cstart[c], cstart[c + 1]
                    _offsets(pos, lo, hi, sigma, radius, cossin, i, order, s0, s1, mox, moy)
                    for s_ in range(s0, s1):
                        j = order[s_]
                        if j == i:
                            continue
                        ox, oy = mox[s_ - s0], moy[s_ - s0]
                        _features(ox, oy, fa, i, pk, psign, pa, pb, fj, need[k], True)  # the score's first
                        v, m = _form(fj, fa, n_pair, pk, psign, ox, oy, i, sf[k], sw[k], sn[k], False)
                        if m > 0:
                            v, m = _form(fj, fa, n_pair, pk, psign, ox, oy, i, sf[k], sw[k], sn[k], True)
                        if pick >= 0 and (v < best or (v == best and j > pick)):
                            continue  # cannot win: its filter need not be known
                        if st == _UNDECIDED:
                            _features(ox, oy, fa, i, pk, psign, pa, pb, fj, need[k], False)
                            if not _pair_filter(fj, fa, n_pair, pk, psign, ox, oy, i, k, code, arg, clen, tf, tw, tn,
                                                thr, stack):
                                continue
                        if pick < 0 or v > best or (v == best and j < pick):
                            best = v
                            pick = j
            else:  # random: the largest (uniform, -index) key over every candidate, struck out until one passes
                base = i * n
                kl, kh = klo[k], khi[k]
                m = np.int64(0)
                for j in range(n):
                    key[j] = uniform_key(_bits(base + j, kl, kh), j)
                    m = max(m, key[j])
                own = key[i]
                key[i] = 0  # nobody asks itself
                tries = 0
                while tries <= RETRIES:
                    if tries > 0 or m == own:
                        m = np.int64(0)
                        for j in range(n):
                            m = max(m, key[j])
                    if m == 0:
                        break
                    j = 0xFFFFFFFF - (m & 0xFFFFFFFF)
                    c = cell_of[j]
                    if seen[c] != tag:
                        if done[c] != i:
                            _bound_cells(c, c + 1, every, box, xi, yi, reach, fa, i, pk, psign, pa, pb, flo, fhi)
                            done[c] = i
                        state[c] = _cell_filter(c, k, flo, fhi, fa, n_pair, i, code, arg, clen, tf, tw, tn, thr,
                                                stack)
                        seen[c] = tag
                    if state[c] == _TRUE:
                        pick = j
                        break
                    if state[c] == _UNDECIDED:
                        _offsets(pos, lo, hi, sigma, radius, cossin, i, order, slot[j], slot[j] + 1, mox, moy)
                        ox, oy = mox[0], moy[0]
                        _features(ox, oy, fa, i, pk, psign, pa, pb, fj, every, True)
                        if _pair_filter(fj, fa, n_pair, pk, psign, ox, oy, i, k, code, arg, clen, tf, tw, tn, thr,
                                        stack):
                            pick = j
                            break
                        key[j] = 0
                    else:
                        for s_ in range(cstart[c], cstart[c + 1]):
                            key[order[s_]] = 0
                    tries += 1
                if pick < 0 and tries > RETRIES:  # many struck out: read every cell, compute undecided members only
                    m = np.int64(0)
                    for c in range(cells):
                        if seen[c] != tag:
                            if done[c] != i:
                                _bound_cells(c, c + 1, every, box, xi, yi, reach, fa, i, pk, psign, pa, pb, flo, fhi)
                                done[c] = i
                            state[c] = _cell_filter(c, k, flo, fhi, fa, n_pair, i, code, arg, clen, tf, tw, tn,
                                                    thr, stack)
                            seen[c] = tag
                        if state[c] == _FALSE:
                            continue
                        for s_ in range(cstart[c], cstart[c + 1]):
                            j = order[s_]
                            if key[j] <= m:
                                continue
                            if state[c] == _UNDECIDED:
                                _offsets(pos, lo, hi, sigma, radius, cossin, i, order, slot[j], slot[j] + 1, mox,
                                         moy)
                                ox, oy = mox[0], moy[0]
                                _features(ox, oy, fa, i, pk, psign, pa, pb, fj, every, True)
                                if not _pair_filter(fj, fa, n_pair, pk, psign, ox, oy, i, k, code, arg, clen, tf, tw,
                                                    tn, thr, stack):
                                    continue
                            m = key[j]
                    if m > 0:
                        pick = 0xFFFFFFFF - (m & 0xFFFFFFFF)
            out[r, k] = pick
