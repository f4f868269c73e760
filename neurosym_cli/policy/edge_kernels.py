"""Hand-fused CPU kernels (numba) of a dense round's pair work, with their own backward (``compile=fused``).

The dense round (policy/transformer.py, ``CommRound``) spends most of its arithmetic on B N^2 pairs: the edge keys
k_ij = ReLU(W_k o_ij + b_k) and logits l_ij = <q_i, k_ij>, and the edge messages sum_j w_ij ReLU(W_m o_ji + b_m).
As torch ops each is a chain of (B, N, N, D) tensors: a 2 -> D linear (an ``mm`` with two input columns, a poor
fit for BLAS), a ReLU, a product and a sum, each stored for backward. Here each is one pass over the pairs per
receiver with the D-wide edge features in registers; nothing of size B N^2 D is stored: backward recomputes them.
docs/performance.md, 'The compiled step', measures what it buys: a round's forward and backward 2x faster at N = 40
and 3.6x at N = 200 on one thread, storing 6-8x less for backward; slower below about 20 agents, where it is not
used (``FUSED_FROM``); the rest of the step is unchanged.

The sums run in another order than torch's (and ``fastmath`` lets LLVM reassociate them), so the numbers agree
with the eager step up to float32 rounding, not bit for bit: ``compile=off`` stays the reference of every committed
number (tests/test_compile.py compares gradients). numba compiles them for the host CPU, and fast-math lets the
sums' order follow its vector width, so one seed repeats on one machine but not bit for bit across machines of
other widths (without fast-math the kernels ran 1.5-5x slower, losing what they are for). Layouts: the pair views
come as P planes, R[p, b, i, j] = o_ij[p] (keys) or T[p, b, i, j] = o_ji[p] (messages, the sender's view), so the
innermost loop runs over j contiguously. Weight gradients are summed per receiver in float32, then across receivers
in float64.

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


@njit(**_JIT)
def _pre(pre, bias_d, wt, planes, b, i, d):  # pragma: no cover - compiled
    """pre[j] = b[d] + sum_p W[d, p] planes[p, b, i, j]: the edge pre-activation of feature d over j (N,)."""
    n = pre.shape[0]
    for j in range(n):
        pre[j] = bias_d
    for p in range(planes.shape[0]):
        c, r = wt[p, d], planes[p, b, i]
        for j in range(n):
            pre[j] += c * r[j]


@njit(**_JIT)
def _logits_fwd(q, R, wt, bias):  # pragma: no cover - compiled
    """q (B, N, D) scaled queries, R (P, B, N, N), wt (P, D) = W_k^T, bias (D,) -> logits (B, N, N)."""
    nb, n, nd = q.shape
    out = np.zeros((nb, n, n), np.float32)
    pre = np.empty(n, np.float32)
    zero = np.float32(0)
    for b in range(nb):
        for i in range(n):
            o = out[b, i]
            for d in range(nd):
                _pre(pre, bias[d], wt, R, b, i, d)
                qd = q[b, i, d]
                for j in range(n):
                    o[j] += qd * max(pre[j], zero)
    return out


@njit(**_JIT)
def _logits_bwd(g, q, R, wt, bias):  # pragma: no cover - compiled
    """g (B, N, N) the logits' gradient -> gradients of q (B, N, D), R (P, B, N, N), wt (P, D), bias (D,)."""
    nb, n, nd = q.shape
    npl = R.shape[0]
    gq, gR = np.empty_like(q), np.zeros_like(R)
    gw, gb = np.zeros((npl, nd)), np.zeros(nd)
    pre, gp = np.empty(n, np.float32), np.empty(n, np.float32)
    zero = np.float32(0)
    for b in range(nb):
        for i in range(n):
            gi = g[b, i]
            for d in range(nd):
                _pre(pre, bias[d], wt, R, b, i, d)
                qd, acc, sb = q[b, i, d], zero, zero
                for j in range(n):
                    acc += gi[j] * max(pre[j], zero)
                    gp[j] = gi[j] * qd if pre[j] > zero else zero  # through the ReLU
                    sb += gp[j]
                gq[b, i, d] = acc
                gb[d] += sb
                for p in range(npl):
                    c, r, gr, s = wt[p, d], R[p, b, i], gR[p, b, i], zero
                    for j in range(n):
                        s += gp[j] * r[j]
                        gr[j] += gp[j] * c
                    gw[p, d] += s
    return gq, gR, gw, gb


@njit(**_JIT)
def _messages_fwd(w, T, wt, bias):  # pragma: no cover - compiled
    """w (B, N, N) attention weights, T (P, B, N, N) the senders' views, wt (P, D) = W_m^T, bias (D,) -> the
    aggregate of edge messages sum_j w_ij ReLU(W_m o_ji + b_m) (B, N, D)."""
    nb, n, _ = w.shape
    nd = wt.shape[1]
    out = np.empty((nb, n, nd), np.float32)
    pre = np.empty(n, np.float32)
    zero = np.float32(0)
    for b in range(nb):
        for i in range(n):
            wi = w[b, i]
            for d in range(nd):
                _pre(pre, bias[d], wt, T, b, i, d)
                acc = zero
                for j in range(n):
                    acc += wi[j] * max(pre[j], zero)
                out[b, i, d] = acc
    return out


@njit(**_JIT)
def _messages_bwd(g, w, T, wt, bias):  # pragma: no cover - compiled
    """g (B, N, D) the aggregate's gradient -> gradients of w (B, N, N), T (P, B, N, N), wt (P, D), bias (D,)."""
    nb, n, _ = w.shape
    npl, nd = wt.shape
    gwt, gT = np.zeros_like(w), np.zeros_like(T)
    gw, gb = np.zeros((npl, nd)), np.zeros(nd)
    pre, gp = np.empty(n, np.float32), np.empty(n, np.float32)
    zero = np.float32(0)
    for b in range(nb):
        for i in range(n):
            wi, gwi = w[b, i], gwt[b, i]
            for d in range(nd):
                _pre(pre, bias[d], wt, T, b, i, d)
                gd, sb = g[b, i, d], zero
                for j in range(n):
                    gwi[j] += gd * max(pre[j], zero)
                    gp[j] = gd * wi[j] if pre[j] > zero else zero
                    sb += gp[j]
                gb[d] += sb
                for p in range(npl):
                    c, r, gr, s = wt[p, d], T[p, b, i], gT[p, b, i], zero
                    for j in range(n):
                        s += gp[j] * r[j]
                        gr[j] += gp[j] * c
                    gw[p, d] += s
    return gwt, gT, gw, gb


FUSED_FROM = 24
"""agents from which the fused kernels serve a round: below it their fixed cost per call (the autograd function,
the copies into planes, numba's dispatch, short inner loops) outweighs what they save, measured on one thread
(docs/performance.md, 'The compiled step': a round's forward and backward 0.82x eager at N = 10, 1.0x at 20, 2.0x
at 40, 3.6x at 200)"""


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
    planes, wt, bias = np.zeros((p, 1, 2, 2), np.float32), np.zeros((p, 1), np.float32), np.zeros(1, np.float32)
    _logits_bwd(g, q, planes, wt, bias)
    _logits_fwd(q, planes, wt, bias)
    _messages_fwd(g, planes, wt, bias)
    _messages_bwd(q, g, planes, wt, bias)
    _WARM.append(time.perf_counter() - t0)
    compiling.compiled(_WARM[0], shapes=0)


def _np(t: Tensor) -> np.ndarray:
    return t.detach().contiguous().numpy()


def _planes(rel: Tensor, sender: bool) -> Tensor:
    """(B, N, N, P) -> (P, B, N, N) contiguous: R[p, b, i, j] = o_ij, or with ``sender`` T[p, b, i, j] = o_ji."""
    return rel.detach().permute(3, 0, 2, 1).contiguous() if sender else rel.detach().permute(3, 0, 1, 2).contiguous()


def _weight_grads(gw: np.ndarray, gb: np.ndarray, like: Tensor) -> tuple[Tensor, Tensor]:
    """float64 sums (P, D), (D,) -> the linear's weight (D, P) and bias (D,) gradients in its dtype."""
    return torch.from_numpy(gw).t().to(like.dtype), torch.from_numpy(gb).to(like.dtype)


class _PairPass(torch.autograd.Function):
    """One pass over the pairs, keys' or messages': (x, rel, W, b, sender) -> out, with x the scaled queries (keys'
    logits, planes of o_ij) or the round's weights (messages, planes of the sender's view o_ji)."""

    @staticmethod
    def forward(ctx, x: Tensor, rel: Tensor, weight: Tensor, bias: Tensor,  # type: ignore[override]
                sender: bool) -> Tensor:
        planes, wt = _planes(rel, sender), weight.detach().t().contiguous()
        ctx.sender = sender
        ctx.save_for_backward(x, planes, wt, bias)
        fwd = _messages_fwd if sender else _logits_fwd
        return torch.from_numpy(fwd(_np(x), planes.numpy(), wt.numpy(), _np(bias)))

    @staticmethod
    def backward(ctx, g: Tensor):  # type: ignore[override]
        x, planes, wt, bias = ctx.saved_tensors
        bwd = _messages_bwd if ctx.sender else _logits_bwd
        gx, gp, gw, gb = bwd(_np(g), _np(x), planes.numpy(), wt.numpy(), _np(bias))
        # planes[p, b, i, j] is o_ij, or o_ji for the sender's view: its gradient goes back to rel[b, i, j, p] or
        # rel[b, j, i, p]
        back = (1, 3, 2, 0) if ctx.sender else (1, 2, 3, 0)
        return torch.from_numpy(gx), torch.from_numpy(gp).permute(*back), *_weight_grads(gw, gb, wt), None


def key_logits(q: Tensor, rel: Tensor, key_edge: nn.Linear) -> Tensor:
    """l_ij = <q_i, ReLU(W_k o_ij + b_k)>: q (B, N, D) scaled queries, rel (B, N, N, P) -> (B, N, N)."""
    return _PairPass.apply(q, rel, key_edge.weight, key_edge.bias, False)


def edge_messages(w: Tensor, rel: Tensor, msg_edge: nn.Linear) -> Tensor:
    """sum_j w_ij ReLU(W_m o_ji + b_m): w (B, N, N) the round's weights (after dropout), rel (B, N, N, P) ->
    (B, N, D)."""
    return _PairPass.apply(w, rel, msg_edge.weight, msg_edge.bias, True)
