"""How much memory a rollout of the transformer needs, estimated before anything is allocated, so that a team that
cannot fit is one line (with the largest size that fits) instead of an out-of-memory crash.

The estimate counts the float32 tensors a step keeps alive, per episode (B) and per step (T when training: BPTT
keeps every step's activations for the backward pass; one step plus temporaries when evaluating):

* the dense path (tf-full, hard-attn, dt; every provider below ``task.sparse_from``): per pair of agents, N^2 of
  them, o_ij and per round the keys, logits, weights and edge messages, plus the dense collision geometry below
  ``sparse_from``;
* the sparse path (prog, dist, comm-range, expo, no-comm from ``sparse_from`` on): per picked pair, N K of them,
  the two views and per round the keys, messages and weights; per agent the embeddings and the post-attention
  block; the collision pairs within the ramps' reach; and once,
  the filter scan's chunk (tasks/pairs.py ``PAIR_CHUNK``), which no step keeps.

The constants were fitted to peak resident memory measured by benchmarks/bench_swarm.py (docs/performance.md,
section 15, where the measurements and the estimates stand side by side).
"""

from __future__ import annotations

from ..config import ModelConfig
from ..errors import ConfigError

BASE_BYTES = 350 * 2 ** 20
"""the interpreter, torch, numba and the model: the peak of a small run"""
PAIR_FLOATS = 4  # per pair of the dense path: o_ij, logits, weights
ROUND_FLOATS_KEPT = 5  # x D per pair and round that BPTT keeps per step (keys pre- and post-ReLU, key x query, ...)
ROUND_FLOATS_LIVE = 2  # x D per pair and round alive at once in an evaluation step (no graph kept)
GEOMETRY_FLOATS = 12  # per pair below sparse_from: distances, same-group, weights, slopes, ramp
PICK_FLOATS = 6 + 9 * 16  # per picked pair and round at D = 16: the two views, keys, messages, weights (scaled by D)
AGENT_ROUND_FLOATS = 48  # x D per agent and round (embedding, query, value, aggregate, LayerNorms, FFN, dynamics)
RAMP_PAIR_BYTES = 60 * 24  # per agent: the collision pairs within reach a step keeps (about 60 at the swarm density)
SCAN_BYTES = 12 * 4  # per pair of the filter scan's chunk: offsets, features, masks, scores


def estimate_bytes(n: int, *, batch: int, horizon: int, rounds: int, model: ModelConfig, k: int, dense: bool,
                   training: bool, sparse_from: int) -> int:
    """Peak bytes of a rollout of ``batch`` episodes of ``n`` agents over ``horizon`` steps (training) or of one
    evaluation step, for the dense path (``dense``) or a provider of ``k`` picks per round."""
    from ..tasks.pairs import PAIR_CHUNK

    d = model.width
    sparse = not dense and n >= sparse_from
    per_step = n * rounds * AGENT_ROUND_FLOATS * d * 4
    if sparse:
        per_step += n * k * rounds * PICK_FLOATS * d // 16 * 4
    else:
        per_step += n * n * (PAIR_FLOATS + rounds * (ROUND_FLOATS_KEPT if training else ROUND_FLOATS_LIVE) * d) * 4
    per_step += n * n * GEOMETRY_FLOATS * 4 if n < sparse_from else n * RAMP_PAIR_BYTES
    scan = min(PAIR_CHUNK, batch * n * n) * SCAN_BYTES if sparse else 0
    return BASE_BYTES + batch * (horizon if training else 1) * per_step + scan


def largest_fitting(fits, limit: int = 1 << 20) -> int:
    """The largest n >= 1 with ``fits(n)`` true (fits decreasing in n), by doubling then bisection; 0 if none."""
    if not fits(1):
        return 0
    lo, hi = 1, 2
    while hi <= limit and fits(hi):
        lo, hi = hi, hi * 2
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return lo


def available_bytes() -> int:
    """Memory this process may still take: MemAvailable of /proc/meminfo (Linux), else 16 GiB."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 16 * 2 ** 30


class DoesNotFit(Exception):
    """Mixed into the ConfigError of a team that cannot fit, so `neurosym stress` can tell it from a missing model."""


class TooLarge(ConfigError, DoesNotFit):
    """A team that does not fit in memory (module level: it crosses from a worker process to the pipeline's)."""


def require_fits(what: str, n: int, *, batch: int, horizon: int, rounds: int, model: ModelConfig, k: int,
                 dense: bool, training: bool, sparse_from: int, limit: int | None = None) -> int:
    """The estimate in bytes, or a one-line ConfigError when it exceeds ``limit`` (default: the memory available
    now), naming the estimate and the largest team that fits. ``what`` names the run ('tf-full evaluation')."""
    limit = available_bytes() if limit is None else limit
    run = dict(batch=batch, horizon=horizon, rounds=rounds, model=model, k=k, dense=dense, training=training,
               sparse_from=sparse_from)  # everything but the team size
    need = estimate_bytes(n, **run)
    if need <= limit:
        return need
    best = largest_fitting(lambda m: estimate_bytes(m, **run) <= limit, limit=max(n, 2))
    gb = 2 ** 30
    fits = f"the largest team that fits is N = {best:,}" if best else "no team fits"
    raise TooLarge(f"N = {n:,} agents does not fit: {what} needs about {need / gb:.1f} GB ({batch} episode(s) at "
                      f"once{f', T = {horizon} steps kept for BPTT' if training else ''}), {limit / gb:.1f} GB are "
                      f"available; {fits} (estimate: neurosym_cli/policy/footprint.py)")
