"""Pairs of agents without the N x N tensors, for teams of thousands (docs/performance.md, section 15).

Three tools, each exact against its dense counterpart:

* :class:`Offsets`, the observation o_ij = x_j - x_i + eps_ij computed only where it is read: at the B N K pairs
  a sparse round asks for (with gradients) and in chunks of receivers for a program's filter scan (without).
* :func:`close_pairs`, the unordered pairs closer than a radius, found by a cell list (spatial hash): O(N) work for
  a swarm of bounded density, where the dense ramp is O(N^2). The collision ramps and counts of the planar tasks
  use it from ``task.sparse_from`` agents on.
* :func:`nearest`, each agent's k nearest others by a chunked scan (dist's picks), never holding (B, N, N).

Noise semantics (``counter_normal``): at N >= ``task.sparse_from`` every observation draws one 62-bit key per
episode from the episode's random source (the same stream the dense path draws its (B, N, N, 2) normals from), and
eps_ij is a fixed function of (key, i, j): reading a pair twice gives the same value, and reading fewer pairs draws
nothing else, so results do not depend on the chunk size or on which pairs a provider reads. Below
``sparse_from`` the dense path draws as it always did (the paper tasks' numbers stay bitwise the same).
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

from ..utils.lazy import LazyModule

if TYPE_CHECKING:
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")

PAIR_CHUNK = 1 << 21
"""pairs (B x receivers x N) an all-pairs scan holds at a time: each float32 feature of a chunk is 8 MiB, so a
program's filter scan over v1's eight features stays under about 150 MiB whatever N is"""
MAX_AGENTS = 46_340
"""the counter of pair (i, j) is i N + j in a signed 32-bit integer (the hash's input): teams up to this size"""


def rows_per_chunk(batch: int, n: int, budget: int = PAIR_CHUNK) -> int:
    """Receivers per chunk so that a chunk holds at most ``budget`` pairs (at least one receiver)."""
    return max(1, budget // max(batch * n, 1))


def _mix32(x: Tensor) -> Tensor:
    """A 32-bit integer hash (xor-shift-multiply, lowbias32's first constant and MurmurHash2's), on int32 tensors:
    products wrap modulo 2^32 as the hash wants (torch's integer kernels wrap; tests/test_pairs.py checks it
    against the same hash in int64), and every right shift is masked, so it is a logical one."""
    x = x ^ ((x >> 16) & 0xFFFF)
    x = x * 0x7FEB352D
    x = x ^ ((x >> 15) & 0x1FFFF)
    x = x * 0x5BD1E995
    return x ^ ((x >> 16) & 0xFFFF)


def counter_bits(key: Tensor, counter: Tensor) -> Tensor:
    """32 random bits per counter: key (B,) int64 (62 bits), counter (B, ...) int32 (i N + j) -> (B, ...) int32.
    int32, not int64: AVX2 has no 64-bit multiply, and the hash is the scan's largest cost."""
    shape = (-1,) + (1,) * (counter.dim() - 1)
    lo = (key & 0x7FFFFFFF).to(torch.int32).view(shape)
    hi = ((key >> 31) & 0x7FFFFFFF).to(torch.int32).view(shape)
    return _mix32(_mix32(counter + lo) ^ hi)


_TABLES: dict = {}


def _box_muller_tables(device) -> tuple[Tensor, Tensor, Tensor]:
    """(65536,) float32 each: the Box-Muller radius sqrt(-2 ln u1) and cos, sin of 2 pi u2 at the 16-bit levels
    u = (k + 0.5) / 65536: looked up instead of computed per pair (four transcendentals per pair were most of the
    scan's time)."""
    key = str(device)
    if key not in _TABLES:
        u = (torch.arange(65536, dtype=torch.float32, device=device) + 0.5) * (1.0 / 65536)
        a = (2 * torch.pi) * u
        _TABLES[key] = (torch.sqrt(-2.0 * torch.log(u)), torch.cos(a), torch.sin(a))
    return _TABLES[key]


def counter_normal(key: Tensor, counter: Tensor) -> Tensor:
    """(B, ...) counters -> (B, ..., 2) standard normals by Box-Muller from the two 16-bit halves of one hash (the
    radius is cut at 4.9 sigma, the angle has 65,536 levels: plenty for an observation noise)."""
    h = counter_bits(key, counter)
    radius, cos, sin = _box_muller_tables(counter.device)
    r = radius[(h >> 16) & 0xFFFF]
    a = h & 0xFFFF
    return torch.stack([r * cos[a], r * sin[a]], -1)


def counter_uniform(key: Tensor, counter: Tensor) -> Tensor:
    """(B, ...) counters -> (B, ...) float32 uniforms in (0, 1), 24 bits each."""
    return (((counter_bits(key, counter) >> 8) & 0xFFFFFF).float() + 0.5) * (1.0 / (1 << 24))


def uniform_rows(key: Tensor, first: int, stop: int, n: int) -> Tensor:
    """(B, stop - first, N) float32: counter_uniform(key, i N + j) of receivers first..stop-1 (a random rule's
    scores in the filter scan), by the compiled kernel on a CPU (the same numbers)."""
    from .pair_kernels import AVAILABLE

    if not (AVAILABLE and key.device.type == "cpu"):
        return counter_uniform(key, pair_counter(first, stop, n, key.device).unsqueeze(0).expand(key.shape[0], -1, -1))
    import numpy as np

    from .pair_kernels import uniform_rows as kernel

    out = torch.empty(key.shape[0], stop - first, n)
    for e, k in enumerate(key.tolist()):
        kernel(np.int64(n), np.int64(k & 0x7FFFFFFF), np.int64((k >> 31) & 0x7FFFFFFF), np.int64(first), out[e].numpy())
    return out


def pair_counter(first: int, stop: int, n: int, device) -> Tensor:
    """(stop - first, N) int32: the counter i N + j of receivers first..stop-1 and every j."""
    return torch.arange(first * n, stop * n, device=device, dtype=torch.int32).view(stop - first, n)


class Offsets:
    """A bucket's o_ij = x_j - x_i + sigma eps_ij (B, N, N, 2), computed where read: ``at`` for given pairs (with
    gradients to the positions), ``rows`` for a chunk of receivers, ``dense`` for all (what a dense provider needs).
    eps_ij = counter_normal(key, i N + j) (module docstring)."""

    def __init__(self, pos: Tensor, noise_std: float, key: Tensor):
        if pos.shape[1] > MAX_AGENTS:
            from ..errors import ConfigError

            raise ConfigError(f"{pos.shape[1]:,} agents: the sparse path's noise counters serve teams of up to "
                              f"{MAX_AGENTS:,} (tasks/pairs.py MAX_AGENTS)")
        self.pos, self.noise_std, self.key = pos, noise_std, key  # (B, N, 2) world units, std, (B,) int64

    @property
    def shape(self) -> tuple[int, int, int, int]:
        b, n = self.pos.shape[:2]
        return (b, n, n, 2)

    @property
    def device(self) -> torch.device:
        return self.pos.device

    def at(self, recv: Tensor, send: Tensor) -> Tensor:
        """recv, send (B, ...) long agent indices -> (B, ..., 2) receiver recv's view of agent send."""
        b, n = self.pos.shape[:2]
        bi = torch.arange(b, device=recv.device).view((b,) + (1,) * (recv.dim() - 1))
        o = self.pos[bi, send] - self.pos[bi, recv]
        if self.noise_std > 0:
            o = o + self._noise_at((recv * n + send).to(torch.int32))
        return o

    def _noise_at(self, counter: Tensor) -> Tensor:
        """(B, ...) int32 counters -> (B, ..., 2) sigma eps: by the compiled loop on a CPU (pair_kernels.noise_at,
        the same numbers as the torch ops, which serve elsewhere)."""
        if not (COMPILED_LOOPS and _numba_on(self.pos)):
            return self.noise_std * counter_normal(self.key, counter)
        import numpy as np

        from .pair_kernels import noise_at

        b = counter.shape[0]
        flat = counter.reshape(b, -1).to(torch.int64).contiguous()
        out = torch.empty(flat.shape + (2,))
        keys = self.key.tolist()
        lo = np.array([k & 0x7FFFFFFF for k in keys], np.int64)
        hi = np.array([(k >> 31) & 0x7FFFFFFF for k in keys], np.int64)
        noise_at(flat.numpy(), lo, hi, np.float32(self.noise_std), *[t.numpy() for t in _box_muller_tables("cpu")],
                 out.numpy())
        return out.view(tuple(counter.shape) + (2,))

    def rows(self, first: int, stop: int) -> Tensor:
        """(B, stop - first, N, 2): receivers first..stop-1, every j; [r, j] = x_j - x_(first + r) + noise. Without
        gradients on a CPU, by the compiled kernel (tasks/pair_kernels.py: the same numbers)."""
        n = self.pos.shape[1]
        if self.noise_std > 0 and _compiled(self.pos):
            return self._rows_compiled(first, stop)
        o = self.pos[:, None, :, :] - self.pos[:, first:stop, None, :]
        if self.noise_std > 0:
            o = o + self.noise_std * counter_normal(self.key, pair_counter(first, stop, n, self.device).unsqueeze(0)
                                                    .expand(self.pos.shape[0], -1, -1))
        return o

    def _rows_compiled(self, first: int, stop: int) -> Tensor:
        import numpy as np

        from .pair_kernels import noisy_rows

        b, n = self.pos.shape[:2]
        out = torch.empty(b, stop - first, n, 2)
        tables = [t.numpy() for t in _box_muller_tables(self.pos.device)]
        pos = self.pos.detach().contiguous().numpy()
        keys = self.key.tolist()
        for e in range(b):
            noisy_rows(pos[e], np.int64(keys[e] & 0x7FFFFFFF), np.int64((keys[e] >> 31) & 0x7FFFFFFF), np.int64(first),
                       np.float32(self.noise_std), *tables, out[e].numpy())
        return out

    def dense(self) -> Tensor:
        """(B, N, N, 2): every pair (built in chunks of receivers, so the hash's temporaries stay bounded)."""
        b, n = self.pos.shape[:2]
        c = rows_per_chunk(b, n)
        return torch.cat([self.rows(i, min(i + c, n)) for i in range(0, n, c)], 1)

    def nearest(self, k: int) -> Tensor:
        """(B, N, k) long: each agent's k nearest others by noise-free distance (dist's picks)."""
        return nearest(self.pos, k)


def _compiled(pos: Tensor) -> bool:
    """Whether ``Offsets.rows`` runs the compiled kernel: float32 on a CPU, numba present, no gradient wanted."""
    return _numba_on(pos) and pos.dtype == torch.float32 and not (torch.is_grad_enabled() and pos.requires_grad)


def _numba_on(pos: Tensor) -> bool:
    """Whether the compiled loops (tasks/pair_kernels.py) can serve this tensor: a CPU with numba."""
    from .pair_kernels import AVAILABLE

    return AVAILABLE and pos.device.type == "cpu" and pos.dtype in (torch.float32, torch.float64)


def nearest(pos: Tensor, k: int) -> Tensor:
    """(B, N, 2) positions -> (B, N, k) long: each agent's k nearest others, nearest first (self excluded), by a
    scan over chunks of receivers under no_grad (memory: one chunk of PAIR_CHUNK distances)."""
    b, n = pos.shape[:2]
    k = max(min(k, n - 1), 0)
    c = rows_per_chunk(b, n)
    out = []
    with torch.no_grad():
        for i in range(0, n, c):
            d = torch.cdist(pos[:, i:i + c], pos)  # (B, c, N)
            d.diagonal(offset=i, dim1=-2, dim2=-1).fill_(float("inf"))
            out.append(d.topk(k, dim=-1, largest=False).indices)
    return torch.cat(out, 1)


def close_pairs(pos: Tensor, radius: float, inclusive: bool = False) -> tuple[Tensor, Tensor]:
    """The unordered pairs closer than ``radius`` (world units) by a cell list: pos (B, N, 2) -> (first, second),
    each (P,) long flat indices b N + i < b N + j, with safe_norm(x_i - x_j) < radius exactly as the dense ramp
    computes it (<= with ``inclusive``). No gradients (indices only). Work and memory O(N c) for c agents per
    cell."""
    from .base import safe_norm

    b, n = pos.shape[:2]
    dev = pos.device
    with torch.no_grad():
        flat = pos.reshape(-1, 2)
        # cells a hair wider than the radius: a pair closer than it is then always in adjacent cells, whatever the
        # rounding of pos / h
        cell = torch.floor(pos / (radius * (1 + 1e-6))).long()  # (B, N, 2)
        cell = cell - cell.amin(1, keepdim=True) + 1  # >= 1: the neighbours -1 stay >= 0
        w = int(cell[..., 0].max()) + 2
        hgt = int(cell[..., 1].max()) + 2
        key = ((torch.arange(b, device=dev).view(b, 1) * hgt + cell[..., 1]) * w + cell[..., 0]).reshape(-1)
        order = key.argsort()
        sorted_key = key[order]
        offs = torch.tensor([dy * w + dx for dy in (-1, 0, 1) for dx in (-1, 0, 1)], device=dev)
        query = key[:, None] + offs[None, :]  # (B N, 9) the neighbour cells of each agent
        if _numba_on(pos) and COMPILED_LOOPS:  # the pairs and their exact test by the compiled loop
            return _pairs_compiled(flat, order, sorted_key, query, radius, inclusive)
        if _numba_on(pos):  # candidates by the compiled loop, a hair beyond the radius; the exact test below
            first, second = _pairs_compiled(flat.double(), order, sorted_key, query, radius * (1 + 1e-4), None)
        else:
            start = torch.searchsorted(sorted_key, query, right=False).reshape(-1)
            count = torch.searchsorted(sorted_key, query, right=True).reshape(-1) - start
            row = torch.repeat_interleave(torch.arange(count.numel(), device=dev), count)  # (C,) candidate -> query
            offset = torch.arange(row.numel(), device=dev) - (torch.cumsum(count, 0) - count)[row]
            first, second = row // 9, order[start[row] + offset]
            keep = first < second
            first, second = first[keep], second[keep]
        d = safe_norm(flat[first] - flat[second])
        close = d <= radius if inclusive else d < radius
        return first[close], second[close]


COMPILED_LOOPS = True
"""close_pairs' cell ranges by ``cell_ranges``' table where its span allows and its exact test inside the compiled
loop, Offsets.at's noise by ``noise_at``, the collision ramps by ``near_ramps``' kernels (False: torch.searchsorted
and torch's test, counter_normal's ops and the ramps' torch ops, the same numbers; benchmarks/bench_swarm_retrain.py
compares their speed)"""
COMPILED_RAMPS = True
"""``near_ramps`` by its kernels (False: its torch ops alone, the same numbers at threads=1; the benchmark's path
'ramps-torch' measures what the kernels buy)"""


def _pairs_compiled(flat: Tensor, order: Tensor, sorted_key: Tensor, query: Tensor, radius: float,
                    inclusive: bool | None) -> tuple[Tensor, Tensor]:
    """close_pairs' pairs (first < second, in its order, its exact test) by tasks/pair_kernels.py ``cell_pairs``
    (``inclusive=None``: the candidates within ``radius`` by squared distance, for a torch test to follow);
    each query cell's range of the sorted keys by ``cell_ranges`` (a table over the keys' span: torch.searchsorted's
    ranges, where a cell holds agents), or by torch.searchsorted where that span is much wider than the team."""
    from .pair_kernels import cell_pairs, cell_ranges

    q = query.reshape(-1)
    span = int(sorted_key[-1] - sorted_key[0]) + 1
    if COMPILED_LOOPS and span <= 8 * sorted_key.numel() + 1024:
        start = torch.empty_like(q)
        count = torch.empty_like(q)
        cell_ranges(sorted_key.contiguous().numpy(), q.contiguous().numpy(), start.numpy(), count.numpy())
    else:
        start = torch.searchsorted(sorted_key, q, right=False)
        count = torch.searchsorted(sorted_key, q, right=True) - start
    total = int(count.sum())
    first = torch.empty(total, dtype=torch.long)
    second = torch.empty(total, dtype=torch.long)
    f = flat.detach().contiguous().numpy()
    m = cell_pairs(f, order.contiguous().numpy(), start.contiguous().numpy(), count.contiguous().numpy(),
                   f.dtype.type(radius), inclusive is not None, bool(inclusive), first.numpy(), second.numpy())
    return first[:m], second[:m]


def near_ramps(flat: Tensor, first: Tensor, second: Tensor, same: Tensor, weight: Tensor, slope: Tensor, batch: int,
               n: int) -> Tensor:
    """(B,) the sum over the given pairs of relu(2 p - d_ij slope), d_ij = safe_norm(x_i - x_j) (the collision
    ramps of tasks/formation.py over ``close_pairs``): flat (B N, 2) positions, first, second (P,) flat indices,
    same (P,) bool (the pair is of one group), weight, slope (2,) the ramp's p and p / d within a group and across.
    On a CPU with numba, float32, one compiled pass each way (tasks/pair_kernels.py ramp_sums, ramp_grads) doing
    torch's float32 arithmetic in torch's one-thread order, so the sums and their gradients are the torch ops' bit
    for bit at threads=1, the default (tests/test_pairs.py); with more threads torch's index backward splits its
    sums by thread, and the two agree to float rounding, as torch's own numbers across thread counts do. Else
    those torch ops."""
    from .base import safe_norm

    kind = (~same).long()  # (P,) 0 within a group, 1 across: the index into weight and slope
    if COMPILED_LOOPS and COMPILED_RAMPS and _numba_on(flat) and flat.dtype == weight.dtype == torch.float32:
        return _near_ramps_function().apply(flat, first, second, kind, weight, slope, batch, n)
    d = safe_norm(flat[first] - flat[second])  # (P,)
    return flat.new_zeros(batch).index_add(0, first // n, torch.relu(2 * weight[kind] - d * slope[kind]))


@functools.cache
def _near_ramps_function() -> type:
    """``near_ramps`` by the compiled kernels as an autograd function with their own backward (the torch ops'
    gradients, bit for bit); built on first use, so that importing this module does not import torch."""
    from torch.autograd.function import once_differentiable

    from .pair_kernels import ramp_grads, ramp_sums

    class NearRamps(torch.autograd.Function):
        @staticmethod
        def forward(ctx, flat, first, second, kind, weight, slope, batch, n):
            f, a, s, k, w, sl = (t.detach().contiguous() for t in (flat, first, second, kind, weight, slope))
            out = torch.zeros(batch, dtype=flat.dtype)
            dist = torch.empty(a.numel(), dtype=flat.dtype)
            ramp_sums(f.numpy(), a.numpy(), s.numpy(), k.numpy(), w.numpy(), sl.numpy(), n, out.numpy(),
                      dist.numpy())
            ctx.save_for_backward(f, a, s, k, w, sl, dist)
            ctx.n = n
            return out

        @staticmethod
        @once_differentiable
        def backward(ctx, grad):
            f, a, s, k, w, sl, dist = ctx.saved_tensors
            g_first, g_second = torch.zeros_like(f), torch.zeros_like(f)
            ramp_grads(f.numpy(), a.numpy(), s.numpy(), k.numpy(), w.numpy(), sl.numpy(), ctx.n, dist.numpy(),
                       grad.contiguous().numpy(), g_first.numpy(), g_second.numpy())
            return g_first + g_second, None, None, None, None, None, None, None

    return NearRamps


def within(pos: Tensor, radius: float) -> Tensor:
    """(B, N, 2) positions -> (B, N, K) long: every other agent at most ``radius`` away, padded with -1 (nobody) to
    K, the bucket's largest degree (comm-range's picks of a large team), by the cell list."""
    b, n = pos.shape[:2]
    with torch.no_grad():
        first, second = close_pairs(pos, radius, inclusive=True)
        recv, send = torch.cat([first, second]), torch.cat([second, first])
        recv, order = recv.sort(stable=True)
        send = send[order] % n
        count = torch.bincount(recv, minlength=b * n)
        k = int(count.max()) if count.numel() else 0
        slot = torch.arange(recv.numel(), device=pos.device) - (torch.cumsum(count, 0) - count)[recv]
        out = torch.full((b * n, k), -1, dtype=torch.long, device=pos.device)
        out[recv, slot] = send
        return out.view(b, n, k)
