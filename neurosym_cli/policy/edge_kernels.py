"""Hand-fused CPU kernels (numba) of a dense round's pair work, with their own backward (``compile=fused``).

The dense round (policy/transformer.py, ``CommRound``) spends most of its arithmetic on B N^2 pairs: the edge keys
k_ij = ReLU(W_k o_ij + b_k) and logits l_ij = <q_i, k_ij>, and the edge messages sum_j w_ij ReLU(W_m o_ji + b_m).
As torch ops each is a chain of (B, N, N, D) tensors: a 2 -> D linear (an ``mm`` with two input columns, a poor
fit for BLAS), a ReLU, a product and a sum, each stored for backward. Here each is one pass over the pairs per
pair with the D-wide edge features in registers; nothing of size B N^2 D is stored: backward recomputes them.
docs/performance.md, 'The compiled step', measures what it buys (``FUSED_FROM``: the team size from which they
serve); the rest of the step is unchanged.

The sums run in another order than torch's, so the numbers agree with the eager step up to float32 rounding, not
bit for bit: ``compile=off`` stays the reference of every committed number (tests/test_compile.py compares
gradients). Layout: the views are read in place from rel (B, N, N, P), o_ij at [b, i, j] (keys) and the sender's
view o_ji at [b, j, i] (messages), and the innermost loops run over the D features of one pair. Weight gradients
are summed per receiver in float32, then across receivers in float64.

Shapes: B episodes, N agents, D model width, P the task's pair width.
"""

from __future__ import annotations

import time

import numpy as np
import torch
from torch import Tensor, nn

from ..tasks.pair_kernels import AVAILABLE, njit
from ..utils import compiling

__all__ = ["AVAILABLE", "serves", "key_logits", "edge_messages"]

_JIT = dict(cache=True, nogil=True, fastmath=True, error_model="numpy", boundscheck=False)


@njit(inline="always", **_JIT)
def _edge(e, wt, bias, o):  # pragma: no cover - compiled
    """e[d] = b[d] + sum_p W[d, p] o[p]: one pair's edge pre-activation (D,), from its view o (P,) and wt = W^T."""
    nd = e.shape[0]
    for d in range(nd):
        e[d] = bias[d]
    for p in range(o.shape[0]):
        op, w = o[p], wt[p]
        for d in range(nd):
            e[d] += w[d] * op


@njit(inline="always", **_JIT)
def _edge_back(ge, o, wt, gw_i, go):  # pragma: no cover - compiled
    """Back through ``_edge`` for one pair: ge (D,) the pre-activation's gradient, o (P,) the view -> adds W's
    gradient to gw_i (P, D) and writes the view's gradient go (P,) = W^T ge."""
    zero = np.float32(0)
    for p in range(o.shape[0]):
        op, w, gwp, s = o[p], wt[p], gw_i[p], zero
        for d in range(ge.shape[0]):
            gwp[d] += ge[d] * op
            s += ge[d] * w[d]
        go[p] = s


@njit(inline="always", **_JIT)
def _fold(gw, gb, gw_i, gb_i):  # pragma: no cover - compiled
    """Add one receiver's float32 weight and bias gradients (P, D), (D,) to the float64 totals."""
    for d in range(gb.shape[0]):
        gb[d] += gb_i[d]
        for p in range(gw.shape[0]):
            gw[p, d] += gw_i[p, d]


@njit(**_JIT)
def _logits_fwd(q, rel, wt, bias):  # pragma: no cover - compiled
    """q (B, N, D) scaled queries, rel (B, N, N, P) the views o_ij, wt (P, D) = W_k^T, bias (D,) -> logits (B, N, N)."""
    nb, n, nd = q.shape
    out = np.empty((nb, n, n), np.float32)
    k = np.empty(nd, np.float32)
    zero = np.float32(0)
    for b in range(nb):
        for i in range(n):
            qi = q[b, i]
            for j in range(n):
                _edge(k, wt, bias, rel[b, i, j])
                acc = zero
                for d in range(nd):
                    acc += qi[d] * max(k[d], zero)
                out[b, i, j] = acc
    return out


@njit(**_JIT)
def _logits_bwd(g, q, rel, wt, bias):  # pragma: no cover - compiled
    """g (B, N, N) the logits' gradient -> gradients of q (B, N, D), rel (B, N, N, P), wt (P, D), bias (D,)."""
    nb, n, nd = q.shape
    npl = rel.shape[3]
    gq, grel = np.zeros_like(q), np.empty_like(rel)
    gw, gb = np.zeros((npl, nd)), np.zeros(nd)
    gw_i, gb_i = np.empty((npl, nd), np.float32), np.empty(nd, np.float32)
    k, gk = np.empty(nd, np.float32), np.empty(nd, np.float32)
    zero = np.float32(0)
    for b in range(nb):
        for i in range(n):
            qi, gqi = q[b, i], gq[b, i]
            gw_i[:] = zero
            gb_i[:] = zero
            for j in range(n):
                o, gij = rel[b, i, j], g[b, i, j]
                _edge(k, wt, bias, o)
                for d in range(nd):
                    on = k[d] > zero  # through the ReLU
                    gqi[d] += gij * (k[d] if on else zero)
                    gk[d] = gij * qi[d] if on else zero
                    gb_i[d] += gk[d]
                _edge_back(gk, o, wt, gw_i, grel[b, i, j])
            _fold(gw, gb, gw_i, gb_i)
    return gq, grel, gw, gb


@njit(**_JIT)
def _messages_fwd(w, rel, wt, bias):  # pragma: no cover - compiled
    """w (B, N, N) attention weights, rel (B, N, N, P) the views (the sender's o_ji read at [b, j, i]), wt (P, D) =
    W_m^T, bias (D,) -> the aggregate of edge messages sum_j w_ij ReLU(W_m o_ji + b_m) (B, N, D)."""
    nb, n, _ = w.shape
    nd = wt.shape[1]
    out = np.zeros((nb, n, nd), np.float32)
    m = np.empty(nd, np.float32)
    zero = np.float32(0)
    for b in range(nb):
        for i in range(n):
            oi = out[b, i]
            for j in range(n):
                wij = w[b, i, j]
                _edge(m, wt, bias, rel[b, j, i])
                for d in range(nd):
                    oi[d] += wij * max(m[d], zero)
    return out


@njit(**_JIT)
def _messages_bwd(g, w, rel, wt, bias):  # pragma: no cover - compiled
    """g (B, N, D) the aggregate's gradient -> gradients of w (B, N, N), rel (B, N, N, P), wt (P, D), bias (D,)."""
    nb, n, _ = w.shape
    npl, nd = wt.shape
    gwt, grel = np.empty_like(w), np.empty_like(rel)
    gw, gb = np.zeros((npl, nd)), np.zeros(nd)
    gw_i, gb_i = np.empty((npl, nd), np.float32), np.empty(nd, np.float32)
    m, gm = np.empty(nd, np.float32), np.empty(nd, np.float32)
    zero = np.float32(0)
    for b in range(nb):
        for i in range(n):
            gi = g[b, i]
            gw_i[:] = zero
            gb_i[:] = zero
            for j in range(n):
                o, wij = rel[b, j, i], w[b, i, j]
                _edge(m, wt, bias, o)
                acc = zero
                for d in range(nd):
                    on = m[d] > zero
                    acc += gi[d] * (m[d] if on else zero)
                    gm[d] = gi[d] * wij if on else zero
                    gb_i[d] += gm[d]
                gwt[b, i, j] = acc
                _edge_back(gm, o, wt, gw_i, grel[b, j, i])
            _fold(gw, gb, gw_i, gb_i)
    return gwt, grel, gw, gb


FUSED_FROM = 16
"""agents from which the fused kernels serve a round: below it their fixed cost per call (the autograd function,
numba's dispatch) is about what they save, measured on one thread (docs/performance.md, 'The compiled step': a
round's forward and backward 1.0x eager at N = 10, 1.6x at 20, 2.4x at 40, 3.4x at 100)"""


def serves(rel: Tensor) -> bool:
    """Whether the fused kernels serve a dense round over ``rel`` (B, N, N, P): compile=fused in effect, a CPU
    tensor, float32 (numba present: compiling.configure says so when it is not), N >= FUSED_FROM, and no tracer
    (export, torch.compile) recording the round. The first time they do in a process, they are compiled (``_warm``)."""
    if not compiling.fused() or not AVAILABLE or torch.jit.is_tracing() or torch.compiler.is_compiling():
        return False  # a tracer first: under torch.export N is symbolic, and comparing it would pin it
    on = rel.device.type == "cpu" and rel.dtype == torch.float32 and rel.shape[1] >= FUSED_FROM
    if on and not _WARM:
        try:
            _warm(rel.shape[-1])
        except Exception as e:  # numba could not compile them here: the eager round, said once
            said = str(e).strip().splitlines()
            compiling.fall_back(f"the fused kernels did not compile ({type(e).__name__}"
                                + (f": {said[0][:160]})" if said else ")"))
            return False
    return on


_WARM: list[float] = []
"""the seconds the kernels took to compile or load in this process, once they have"""


def _warm(p: int) -> None:
    """Compile the four kernels (or load them from numba's on-disk cache) on tiny inputs of pair width ``p``, and
    count the time in the runtime's compile_seconds: about 6 s cold, under 1 s from the cache."""
    t0 = time.perf_counter()
    q, g = np.zeros((1, 2, 1), np.float32), np.zeros((1, 2, 2), np.float32)
    rel, wt, bias = np.zeros((1, 2, 2, p), np.float32), np.zeros((p, 1), np.float32), np.zeros(1, np.float32)
    _logits_bwd(g, q, rel, wt, bias)
    _logits_fwd(q, rel, wt, bias)
    _messages_fwd(g, rel, wt, bias)
    _messages_bwd(q, g, rel, wt, bias)
    _WARM.append(time.perf_counter() - t0)
    compiling.compiled(_WARM[0], shapes=0)


def _np(t: Tensor) -> np.ndarray:
    return t.detach().contiguous().numpy()


def _weight_grads(gw: np.ndarray, gb: np.ndarray, like: Tensor) -> tuple[Tensor, Tensor]:
    """float64 sums (P, D), (D,) -> the linear's weight (D, P) and bias (D,) gradients in its dtype."""
    return torch.from_numpy(gw).t().to(like.dtype), torch.from_numpy(gb).to(like.dtype)


class _PairPass(torch.autograd.Function):
    """One pass over the pairs, keys' or messages': (x, rel, W, b, sender) -> out, with x the scaled queries (keys'
    logits from o_ij) or the round's weights (messages, from the sender's view o_ji)."""

    @staticmethod
    def forward(ctx, x: Tensor, rel: Tensor, weight: Tensor, bias: Tensor,  # type: ignore[override]
                sender: bool) -> Tensor:
        rel, wt = rel.detach().contiguous(), weight.detach().t().contiguous()
        ctx.sender = sender
        ctx.save_for_backward(x, rel, wt, bias)
        fwd = _messages_fwd if sender else _logits_fwd
        return torch.from_numpy(fwd(_np(x), rel.numpy(), wt.numpy(), _np(bias)))

    @staticmethod
    def backward(ctx, g: Tensor):  # type: ignore[override]
        x, rel, wt, bias = ctx.saved_tensors
        bwd = _messages_bwd if ctx.sender else _logits_bwd
        gx, grel, gw, gb = bwd(_np(g), _np(x), rel.numpy(), wt.numpy(), _np(bias))
        return torch.from_numpy(gx), torch.from_numpy(grel), *_weight_grads(gw, gb, wt), None


def key_logits(q: Tensor, rel: Tensor, key_edge: nn.Linear) -> Tensor:
    """l_ij = <q_i, ReLU(W_k o_ij + b_k)>: q (B, N, D) scaled queries, rel (B, N, N, P) -> (B, N, N)."""
    return _PairPass.apply(q, rel, key_edge.weight, key_edge.bias, False)


def edge_messages(w: Tensor, rel: Tensor, msg_edge: nn.Linear) -> Tensor:
    """sum_j w_ij ReLU(W_m o_ji + b_m): w (B, N, N) the round's weights (after dropout), rel (B, N, N, P) ->
    (B, N, D)."""
    return _PairPass.apply(w, rel, msg_edge.weight, msg_edge.bias, True)
