"""Every interval the project prints, in one place (numpy only; no scipy).

Two kinds of runs, never mixed:

- **evaluation seeds** of ONE trained model (20 per baseline): their spread is episode noise, and their interval
  (``mean_ci``) says how well that one model was measured, not how good the method is;
- **training seeds** (a whole pipeline per seed: oracle, dataset, search, retraining): the runs of the method.
  Across them: the mean with its Student-t 95 % interval (``mean_ci``), the interquartile mean (IQM) with a
  stratified bootstrap 95 % interval (``iqm_ci``), the probability of improvement with its bootstrap interval
  (``improvement_ci``) and the performance profile (``performance_profile``).

The across-seed statistics follow Agarwal et al., "Deep Reinforcement Learning at the Edge of the Statistical
Precipice" (NeurIPS 2021) and its library rliable (archived, not a dependency): IQM is the 25 % trimmed mean over
all runs and tasks (scipy's ``trim_mean``: ``int(0.25 n)`` values cut from each end, so with fewer than 4 runs it
is the mean), bootstrap intervals are percentile intervals of a stratified bootstrap (runs resampled with
replacement within each task; seeded, so reproducible), and the probability of improvement is the Mann-Whitney
U statistic over run pairs, averaged over tasks.

Orientation. Losses are lower-is-better. ``probability_of_improvement(x, y)`` is P(X improves on Y): with
``lower_is_better=True`` that is P(loss_X < loss_Y) + 0.5 P(loss_X = loss_Y), which is rliable's P(X > Y) on the
negated losses. ``normalized_score`` maps a loss to rliable's higher-is-better scale per task and training seed,
like Atari's human-normalized score: (no-comm - loss) / (no-comm - tf-full) with that seed's own tf-full and
no-comm losses, so 1 is the seed's oracle with full communication, 0 is its model that never talks, and above 1
is better than the oracle. Every baseline except dist and no-comm is built on that seed's oracle, so the
normalization compares each to the models it came from.

Scores arrays are shaped (runs, tasks) like rliable's: one row per training seed, one column per task.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np

_T95 = (12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
        2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042)
"""two-sided 95 % Student t quantiles for 1..30 degrees of freedom (the printed tables)"""

_Z975 = 1.959963984540054
"""the standard normal 97.5 % quantile"""

REPS = 50_000
"""bootstrap resamples of the interval estimates (rliable's default for get_interval_estimates)"""

PROFILE_REPS = 2_000
"""bootstrap resamples of a performance profile (rliable's default for create_performance_profile)"""

CAPTION_T = "± = 95 % Student-t interval (t quantile, n - 1 degrees of freedom)"
"""the one ± convention of every table, said in its caption"""


def t95(n: int) -> float:
    """Two-sided 95 % Student t quantile for a sample of ``n`` (n - 1 degrees of freedom); n >= 2.

    Up to 30 degrees of freedom the printed table; beyond, the Cornish-Fisher expansion of the t quantile in
    the normal one (Hill 1970, four terms: within 1e-4 of the exact value there), never the normal 1.96."""
    if n < 2:
        raise ValueError(f"a t interval needs at least 2 samples, got {n}")
    df = n - 1
    if df <= len(_T95):
        return _T95[df - 1]
    z = _Z975
    g1 = (z ** 3 + z) / 4
    g2 = (5 * z ** 5 + 16 * z ** 3 + 3 * z) / 96
    g3 = (3 * z ** 7 + 19 * z ** 5 + 17 * z ** 3 - 15 * z) / 384
    g4 = (79 * z ** 9 + 776 * z ** 7 + 1482 * z ** 5 - 1920 * z ** 3 - 945 * z) / 92160
    return z + g1 / df + g2 / df ** 2 + g3 / df ** 3 + g4 / df ** 4


def mean_ci(xs: Sequence[float]) -> tuple[float, float]:
    """(mean, half-width of its 95 % Student-t interval) of a sample; the half-width is inf for one value (no
    interval from a single run)."""
    n = len(xs)
    if n == 0:
        raise ValueError("mean_ci of an empty sample")
    m = sum(xs) / n
    if n < 2:
        return m, math.inf
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (n - 1))
    return m, t95(n) * sd / math.sqrt(n)


def _trimmed(a: np.ndarray) -> np.ndarray:
    """25 % trimmed mean along the last axis (scipy.stats.trim_mean's cut: int(0.25 n) from each end)."""
    n = a.shape[-1]
    k = int(0.25 * n)
    return np.sort(a, axis=-1)[..., k:n - k].mean(axis=-1)


def iqm(scores: np.ndarray | Sequence[float]) -> float:
    """Interquartile mean over all runs and tasks (rliable's aggregate_iqm): the mean of the middle 50 % of the
    flattened scores; with fewer than 4 values nothing is cut, so it is their mean."""
    a = np.asarray(scores, dtype=float).ravel()
    if a.size == 0:
        raise ValueError("iqm of an empty sample")
    return float(_trimmed(a))


def _as_matrix(scores: np.ndarray | Sequence[float]) -> np.ndarray:
    """(runs, tasks); a 1-D sample is one task."""
    a = np.asarray(scores, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"scores must be (runs, tasks) with at least one of each, got shape {a.shape}")
    return a


def stratified_resamples(scores: np.ndarray, reps: int, rng: np.random.Generator) -> np.ndarray:
    """(reps, runs, tasks): each task's runs resampled with replacement, independently per task (rliable's
    StratifiedBootstrap over runs, tasks kept)."""
    n, m = scores.shape
    idx = rng.integers(0, n, size=(reps, n, m))
    return scores[idx, np.arange(m)]


def _percentile(stats: np.ndarray, size: float) -> tuple[float, float]:
    """The percentile interval of bootstrap statistics (rliable's default method)."""
    lo, hi = np.quantile(stats, [(1 - size) / 2, (1 + size) / 2], axis=0)
    return float(lo), float(hi)


def bootstrap_ci(scores: np.ndarray | Sequence[float], stat: Callable[[np.ndarray], np.ndarray],
                 reps: int = REPS, seed: int = 0, size: float = 0.95) -> tuple[float, float]:
    """Percentile interval of ``stat`` under the stratified bootstrap of ``scores`` (runs, tasks).
    ``stat`` maps (reps, runs, tasks) to (reps,). Seeded: the same call gives the same interval."""
    a = _as_matrix(scores)
    return _percentile(stat(stratified_resamples(a, reps, np.random.default_rng(seed))), size)


def iqm_ci(scores: np.ndarray | Sequence[float], reps: int = REPS, seed: int = 0,
           size: float = 0.95) -> tuple[float, float, float]:
    """(IQM, lower, upper): the interquartile mean and its stratified bootstrap percentile interval."""
    a = _as_matrix(scores)
    lo, hi = bootstrap_ci(a, lambda b: _trimmed(b.reshape(b.shape[0], -1)), reps, seed, size)
    return iqm(a), lo, hi


def _improvement(x: np.ndarray, y: np.ndarray, lower_is_better: bool) -> np.ndarray:
    """P(X improves on Y) of (..., runs_x, tasks) and (..., runs_y, tasks): per task the share of run pairs where X
    is better (ties count one half), then the mean over tasks."""
    if lower_is_better:
        x, y = -x, -y
    d = x[..., :, None, :] - y[..., None, :, :]  # (..., runs_x, runs_y, tasks)
    per_task = ((d > 0) + 0.5 * (d == 0)).mean(axis=(-3, -2))
    return per_task.mean(axis=-1)


def probability_of_improvement(x: np.ndarray | Sequence[float], y: np.ndarray | Sequence[float],
                               lower_is_better: bool = True) -> float:
    """P(X improves on Y), rliable's probability_of_improvement: per task the Mann-Whitney U statistic of X's runs
    against Y's divided by runs_x * runs_y (ties count 1/2), averaged over tasks. ``x``, ``y``: (runs, tasks)
    with the same tasks; lower_is_better (losses): X improves when its loss is lower."""
    a, b = _as_matrix(x), _as_matrix(y)
    if a.shape[1] != b.shape[1]:
        raise ValueError(f"x and y have different task counts: {a.shape[1]} and {b.shape[1]}")
    return float(_improvement(a, b, lower_is_better))


def improvement_ci(x: np.ndarray | Sequence[float], y: np.ndarray | Sequence[float], lower_is_better: bool = True,
                   reps: int = REPS, seed: int = 0, size: float = 0.95) -> tuple[float, float, float]:
    """(P(X improves on Y), lower, upper): the percentile interval resamples X's and Y's runs independently within
    each task (rliable's StratifiedIndependentBootstrap)."""
    a, b = _as_matrix(x), _as_matrix(y)
    p = probability_of_improvement(a, b, lower_is_better)
    rng = np.random.default_rng(seed)
    ra, rb = stratified_resamples(a, reps, rng), stratified_resamples(b, reps, rng)
    lo, hi = _percentile(_improvement(ra, rb, lower_is_better), size)
    return p, lo, hi


def normalized_score(loss: float, tf_full: float, no_comm: float) -> float:
    """(no_comm - loss) / (no_comm - tf_full): 1 at the seed's tf-full, 0 at its no-comm, higher is better.
    Undefined (ValueError) when no-comm is not worse than tf-full on that seed: there is no gap to normalize by."""
    gap = no_comm - tf_full
    if not gap > 0:
        raise ValueError(f"no-comm ({no_comm:g}) is not worse than tf-full ({tf_full:g}): no gap to normalize by")
    return (no_comm - loss) / gap


def performance_profile(scores: np.ndarray | Sequence[Sequence[float]], taus: Sequence[float],
                        reps: int = PROFILE_REPS, seed: int = 0,
                        size: float = 0.95) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """rliable's score distribution (create_performance_profile, use_score_distribution=True): for each tau the
    fraction of all runs and tasks whose (higher-is-better) score exceeds tau, with its stratified bootstrap
    percentile band. ``scores``: (runs, tasks), or one sequence of runs per task when tasks have different run
    counts (each task's runs are resampled within it). Returns (profile, lower, upper), each of len(taus)."""
    if isinstance(scores, np.ndarray) and scores.ndim == 2:
        cols = [scores[:, j] for j in range(scores.shape[1])]
    else:
        cols = [np.asarray(c, dtype=float).ravel() for c in scores]
    cols = [c for c in cols if c.size]
    if not cols:
        raise ValueError("a performance profile of no runs")
    t = np.asarray(taus, dtype=float)
    flat = np.concatenate(cols)
    prof = (flat[:, None] > t).mean(axis=0)
    rng = np.random.default_rng(seed)
    boot = np.concatenate([c[rng.integers(0, c.size, size=(reps, c.size))] for c in cols], axis=1)
    dist = (boot[:, :, None] > t).mean(axis=1)  # (reps, taus)
    lo, hi = np.quantile(dist, [(1 - size) / 2, (1 + size) / 2], axis=0)
    return prof, lo, hi


def across_seeds(values: Sequence[float], reps: int = REPS, seed: int = 0) -> dict:
    """One metric of one baseline over training seeds: n, mean, std, the t half-width (None for one seed: there is
    no interval across one seed), IQM and its stratified bootstrap interval (None for one seed), min and max."""
    v = [float(x) for x in values]
    n = len(v)
    if n == 0:
        raise ValueError("across_seeds of no seeds")
    m, half = mean_ci(v)
    out = {"n": n, "mean": m, "std": float(np.std(v, ddof=1)) if n > 1 else None,
           "ci95": half if n > 1 else None, "min": min(v), "max": max(v), "iqm": iqm(v),
           "iqm_lo": None, "iqm_hi": None}
    if n > 1:
        _, out["iqm_lo"], out["iqm_hi"] = iqm_ci(v, reps, seed)
    return out
