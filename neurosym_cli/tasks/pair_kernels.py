"""Compiled CPU kernel of the sparse path's filter scan (numba): the noisy offsets of a chunk of receivers in one
pass, the counter hash and the Box-Muller look-up fused per pair (about 13x faster than the same arithmetic as
eager torch ops on one core, docs/performance.md section 15). It computes exactly the numbers of the torch code in
tasks/pairs.py (``Offsets.rows``), the reference, which serves gradients, GPUs and machines without numba
(tests/test_pairs.py compares them bit for bit)."""

from __future__ import annotations

import numpy as np

try:  # numba is a dependency; the torch code of tasks/pairs.py is the fallback
    from numba import njit

    AVAILABLE = True
except ImportError:  # pragma: no cover - exercised only on machines without numba
    AVAILABLE = False

    def njit(*args, **kwargs):  # type: ignore[no-redef]
        return lambda f: f

_JIT = dict(cache=True, nogil=True, error_model="numpy", boundscheck=False)
# numba's cache is keyed by the stamp of the function's own file: a kernel that inlines a helper from another file
# (policy/scan_kernels.py and scan_cells.py inline _bits; scan_cells inlines scan_kernels' angle and norm) keeps its
# cached code when only the helper's file changes. After editing a helper, delete the callers' __pycache__/*.nb*
# (a fresh clone, as CI runs, has none).


_M1, _M2 = np.uint32(0x7FEB352D), np.uint32(0x5BD1E995)


@njit(inline="always", **_JIT)
def _mix32(x: np.uint32) -> np.uint32:
    """tasks/pairs.py ``_mix32`` on an unsigned 32-bit value (the same bits as its int32 form). Every step is cast
    back to 32 bits, so the compiler keeps 32-bit vector lanes (1.0 ns a hash against 1.45 with the products
    written in 64 bits and masked)."""
    x = np.uint32(x ^ (x >> np.uint32(16)))
    x = np.uint32(x * _M1)
    x = np.uint32(x ^ (x >> np.uint32(15)))
    x = np.uint32(x * _M2)
    return np.uint32(x ^ (x >> np.uint32(16)))


@njit(inline="always", **_JIT)
def _bits(counter, lo, hi) -> np.uint32:
    """tasks/pairs.py ``counter_bits``: 32 random bits of an int64 counter i N + j under a key's 31-bit halves."""
    return _mix32(np.uint32(_mix32(np.uint32(counter + lo)) ^ np.uint32(hi)))


@njit(**_JIT)
def noisy_rows(pos: np.ndarray, lo: np.int64, hi: np.int64, first: np.int64, sigma: np.float32,
               radius: np.ndarray, cos: np.ndarray, sin: np.ndarray, out: np.ndarray) -> None:
    """out (R, N, 2) float32 <- o_ij of receivers first..first+R-1 of one episode: pos (N, 2) float32, the key's
    31-bit halves lo and hi, the noise std sigma, the Box-Muller tables (65536,) each."""
    n = pos.shape[0]
    for r in range(out.shape[0]):
        i = first + r
        xi, yi = pos[i, 0], pos[i, 1]
        for j in range(n):
            h = _bits(i * n + j, lo, hi)
            rad = radius[h >> np.uint32(16)]
            k = h & np.uint32(0xFFFF)
            out[r, j, 0] = (pos[j, 0] - xi) + sigma * (rad * cos[k])
            out[r, j, 1] = (pos[j, 1] - yi) + sigma * (rad * sin[k])


@njit(**_JIT)
def noise_at(counter: np.ndarray, lo: np.ndarray, hi: np.ndarray, sigma: np.float32, radius: np.ndarray,
             cos: np.ndarray, sin: np.ndarray, out: np.ndarray) -> None:
    """out (B, M, 2) float32 <- sigma times tasks/pairs.py ``counter_normal`` of counters (B, M) int64 (i N + j of
    given pairs) under each episode's key halves lo, hi (B,): the noise of ``Offsets.at``."""
    for e in range(counter.shape[0]):
        for m in range(counter.shape[1]):
            h = _bits(counter[e, m], lo[e], hi[e])
            rad = radius[h >> np.uint32(16)]
            k = h & np.uint32(0xFFFF)
            out[e, m, 0] = sigma * (rad * cos[k])
            out[e, m, 1] = sigma * (rad * sin[k])


@njit(**_JIT)
def uniform_rows(n: np.int64, lo: np.int64, hi: np.int64, first: np.int64, out: np.ndarray) -> None:
    """out (R, N) float32 <- tasks/pairs.py ``counter_uniform`` of counters i N + j, receivers first..first+R-1."""
    for r in range(out.shape[0]):
        i = first + r
        for j in range(n):
            h = _bits(i * n + j, lo, hi)
            out[r, j] = (np.float32((h >> np.uint32(8)) & np.uint32(0xFFFFFF)) + np.float32(0.5)) \
                * np.float32(1.0 / (1 << 24))


@njit(**_JIT)
def cell_ranges(sorted_key: np.ndarray, query: np.ndarray, start: np.ndarray, count: np.ndarray) -> None:
    """start, count (Q,) int64 <- for each query key, its range in sorted_key (K,) int64, ascending: the first index
    of the key and how many there are (torch.searchsorted left, and right minus left), by a table over the keys'
    span; a key absent from sorted_key gets count 0 and start 0 (nothing of it is read)."""
    k0 = sorted_key[0]
    span = sorted_key[-1] - k0 + 1
    first = np.zeros(span, np.int64)
    many = np.zeros(span, np.int64)
    for s in range(sorted_key.shape[0] - 1, -1, -1):
        first[sorted_key[s] - k0] = s
        many[sorted_key[s] - k0] += 1
    for q in range(query.shape[0]):
        k = query[q] - k0
        if 0 <= k < span:
            start[q] = first[k]
            count[q] = many[k]
        else:
            start[q] = 0
            count[q] = 0


@njit(**_JIT)
def cell_pairs(flat: np.ndarray, order: np.ndarray, start: np.ndarray, count: np.ndarray, radius, exact: bool,
               inclusive: bool, first: np.ndarray, second: np.ndarray) -> np.int64:
    """The cell list's pairs (a, s), a < s, in tasks/pairs.py ``close_pairs``' order (agent a = row // 9, its 9
    neighbour cells in turn, each cell's agents in sorted order), kept where safe_norm(x_a - x_s) < radius (<= with
    ``inclusive``) in flat's own float arithmetic, as the torch test computes it (``exact=False``: where the squared
    distance is at most radius squared, a superset for a torch test to follow: the path before the exact test was
    compiled, which benchmarks/bench_swarm_retrain.py's 'before' runs). flat (B N, 2) float32 or float64
    positions, radius of its dtype; order (B N,) agents sorted by cell; start, count (B N 9,) each query's range in
    it; first, second (sum of count,) int64, filled in place; returns how many were kept."""
    eps = flat.dtype.type(1e-12)
    m = 0
    for row in range(start.shape[0]):
        a = row // 9
        ax, ay = flat[a, 0], flat[a, 1]
        for t in range(count[row]):
            s = order[start[row] + t]
            if a < s:
                dx = ax - flat[s, 0]
                dy = ay - flat[s, 1]
                q = dx * dx + dy * dy
                if exact:
                    d = np.sqrt(max(q, eps))
                    keep = d < radius or (inclusive and d == radius)
                else:
                    keep = q <= radius * radius
                if keep:
                    first[m] = a
                    second[m] = s
                    m += 1
    return m


@njit(**_JIT)
def ramp_sums(flat: np.ndarray, first: np.ndarray, second: np.ndarray, kind: np.ndarray, weight: np.ndarray,
              slope: np.ndarray, n: np.int64, out: np.ndarray, dist: np.ndarray) -> None:
    """tasks/pairs.py ``near_ramps``' forward, its torch ops' float32 arithmetic in their order: out (B,) float32 zeros
    += relu(2 p - d slope) of each pair (first, second (P,) flat indices into flat (B N, 2) float32; kind (P,) 0 for
    a pair of one group, 1 across; weight, slope (2,) float32 by kind), added in pair order into its episode
    first // n, as index_add does; dist (P,) <- each pair's d, for the backward."""
    two, eps = np.float32(2), np.float32(1e-12)
    for p in range(first.shape[0]):
        a, s, k = first[p], second[p], kind[p]
        dx = flat[a, 0] - flat[s, 0]
        dy = flat[a, 1] - flat[s, 1]
        d = np.sqrt(max(dx * dx + dy * dy, eps))
        dist[p] = d
        r = two * weight[k] - d * slope[k]
        if not r <= 0:  # relu: a NaN passes, as torch's does
            out[a // n] += r


@njit(**_JIT)
def ramp_grads(flat: np.ndarray, first: np.ndarray, second: np.ndarray, kind: np.ndarray, weight: np.ndarray,
               slope: np.ndarray, n: np.int64, dist: np.ndarray, grad: np.ndarray, g_first: np.ndarray,
               g_second: np.ndarray) -> None:
    """Back through ``ramp_sums`` as autograd goes back through its torch ops, in their float32 arithmetic: grad (B,)
    the sums' gradient -> g_first, g_second (B N, 2) float32 zeros += each pair's gradient at its first and at its
    second agent, in pair order (the two index backwards); the caller adds them."""
    two, eps = np.float32(2), np.float32(1e-12)
    for p in range(first.shape[0]):
        a, s, k = first[p], second[p], kind[p]
        d = dist[p]
        if not two * weight[k] - d * slope[k] > 0:  # relu: no gradient where the ramp is 0
            continue
        dx = flat[a, 0] - flat[s, 0]
        dy = flat[a, 1] - flat[s, 1]
        if not dx * dx + dy * dy >= eps:  # clamp(min=eps): none below it
            continue
        gq = (-grad[a // n] * slope[k]) / (two * d)  # through d = sqrt(q) and the product d slope
        gx = gq * dx + gq * dx  # q = dx dx + dy dy: x * x gives its gradient twice
        gy = gq * dy + gq * dy
        g_first[a, 0] += gx
        g_first[a, 1] += gy
        g_second[s, 0] += -gx
        g_second[s, 1] += -gy
