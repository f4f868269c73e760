"""The evaluation protocol (paper section 4, docs/fidelity.md, 'Evaluation').

Every evaluation seed re-seeds everything: its episodes (the task's fixed test settings, or random episodes)
and their observation noise come from generators derived from the seed alone, so all baselines face the same
episodes, and a seed's numbers do not depend on which other seeds ran beside it. Episodes of all seeds are
batched together, bucketed by agent count.
"""

from __future__ import annotations

import math
from typing import Sequence

import torch

from .tasks.base import Task, Rng, group_by_agents
from .policy.comm import CommProvider
from .policy.transformer import CommTransformer
from .rollout import rollout
from .stats import mean_ci
from .utils.seeding import STREAM_EVAL, STREAM_VAL, generator


def evaluate(
    env: Task,
    policy: CommTransformer,
    comm: CommProvider,
    seeds: Sequence[int],
    device: torch.device,
    detach_state: bool = False,
    split: str = "test",
) -> list[dict[str, float]]:
    """One row per seed: the mean over that seed's episodes of each per-episode metric (time averages).
    ``split``: test (the reported protocol) or val (`neurosym select`'s own episodes, disjoint from the test ones)."""
    stream = {"test": STREAM_EVAL, "val": STREAM_VAL}[split]
    states, keys = [], []
    for s in seeds:
        eps, gens = env.test_episodes(lambda k, s=s: generator(s, stream, k))
        states += eps
        keys += [(s, g) for g in gens]
    sums: dict[int, dict[str, float]] = {s: {} for s in seeds}
    counts = {s: 0 for s in seeds}
    was_training = policy.training
    policy.eval()
    with torch.no_grad():
        for bucket, bkeys in group_by_agents(states, keys):
            rng = Rng([g for _, g in bkeys], device)
            traj = rollout(env, policy, comm, bucket.to(device), rng, env.horizon, detach_state=detach_state)
            per_ep = traj.episode_metrics()
            for e, (s, _) in enumerate(bkeys):
                counts[s] += 1
                for m, v in per_ep.items():
                    sums[s][m] = sums[s].get(m, 0.0) + float(v[e])
    policy.train(was_training)
    return [{"seed": s, "episodes": counts[s], **{m: v / counts[s] for m, v in sums[s].items()}} for s in seeds]


def summarize(rows: Sequence[dict[str, float]]) -> dict[str, dict[str, float]]:
    """Per metric over the evaluation seeds of ONE trained model: mean, sample std (ddof 1), n, and ``ci95``, the
    half-width of the 95 % Student-t interval of the mean (stats.mean_ci; 0 for one seed). That interval is
    episode noise of this one model, how well it was measured, not the uncertainty of the method: that comes
    from training seeds (`neurosym report`, stats.across_seeds)."""
    out = {}
    n = len(rows)
    for m in [k for k in rows[0] if k not in ("seed", "episodes")]:  # the shared metrics, then the task's own
        mean, half = mean_ci([r[m] for r in rows])
        std = math.sqrt(sum((r[m] - mean) ** 2 for r in rows) / (n - 1)) if n > 1 else 0.0
        out[m] = {"mean": mean, "std": std, "ci95": half if n > 1 else 0.0, "n": n}
    return out
