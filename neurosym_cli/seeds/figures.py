"""The figures across training seeds: the loss-degree plane per task and the performance profile."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

from .. import stats
from ..run.layout import SEEDS_PROFILE, seeds_plane_file
from ..utils.io import check_inside
from .read import SeedRun
from .summary import Summary, order, summarize

def plane(runs: Sequence[SeedRun], s: Summary) -> tuple[dict, dict]:
    """The loss-degree plane's data: baseline -> [(seed, max degree, loss)] and baseline -> (mean degree, its t
    half-width or None, mean loss, its t half-width or None)."""
    points = {k: [(r.seed, r.entries[k].mean("max_degree"), r.entries[k].mean("cost")) for r in runs
                  if k in r.entries] for k in s.rows}
    across = {k: (m["max_degree"]["mean"], m["max_degree"]["ci95"], m["cost"]["mean"], m["cost"]["ci95"])
              for k, m in s.rows.items()}
    return points, across


def normalized(by_task: dict[str, Sequence[SeedRun]]) -> tuple[dict[str, list[list[float]]], list[str]]:
    """Per baseline, one list per task of its normalized scores (stats.normalized_score against that training
    seed's own tf-full and no-comm) over the training seeds; and a line per (task, seed) left out (tf-full or
    no-comm missing, or no-comm not worse than tf-full: nothing to normalize by)."""
    tasks = list(by_task)
    out: dict[str, list[list[float]]] = {}
    left: list[str] = []
    for j, task in enumerate(tasks):
        for r in by_task[task]:
            e = r.entries
            if "tf-full" not in e or "no-comm" not in e:
                left.append(f"{task} seed {r.seed}: no tf-full or no-comm")
                continue
            ref, worst = e["tf-full"].mean("cost"), e["no-comm"].mean("cost")
            if not worst > ref:
                left.append(f"{task} seed {r.seed}: no-comm ({worst:.3g}) not worse than tf-full ({ref:.3g})")
                continue
            for k, entry in e.items():
                cols = out.setdefault(k, [[] for _ in tasks])
                cols[j].append(stats.normalized_score(entry.mean("cost"), ref, worst))
    return {k: out[k] for k in order(out)}, left


def draw(by_task: dict[str, Sequence[SeedRun]], out_dir: Path, mix: bool = False) -> list[Path]:
    """The figures across training seeds into ``out_dir``: seeds-<task>.png (the loss-degree plane) per task with
    a run, and seeds-profile.png (the performance profile of normalized loss over tasks and seeds)."""
    import numpy as np

    from ..plotting import profile_plot, seeds_plane

    check_inside(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    made = []
    for task, runs in by_task.items():
        if not runs:
            continue
        s = summarize(runs, mix, reps=2000)  # the figure's intervals are the t ones; no bootstrap drawn
        pts, across = plane(runs, s)
        n = len(s.seeds)
        what = (f"{n} training seeds: one small marker per seed, the mean ± 95 % t-interval across seeds"
                if n > 1 else "1 training seed: no interval across seeds")
        budget = runs[0].settings.get("budget")
        made.append(seeds_plane(pts, across, f"{task} ({budget} budget): loss against max in+out over training "
                                f"seeds\n{what}; lower left is better", out_dir / seeds_plane_file(task)))
    scores, left = normalized(by_task)
    scores = {k: v for k, v in scores.items() if k not in ("tf-full", "no-comm")}  # 1 and 0 by definition
    if scores:
        all_vals = [x for cols in scores.values() for c in cols for x in c]
        lo, hi = max(min(all_vals + [0.0]), -1.0), min(max(all_vals + [1.0]), 2.0)  # beyond: flat, left out
        outside = sum(not lo <= x <= hi for x in all_vals)
        taus = np.linspace(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo), 301)
        curves = {k: stats.performance_profile(v, taus) for k, v in scores.items()}
        n_runs = sum(len(c) for c in next(iter(scores.values())))
        note = (f"runs = (task, training seed) pairs: {', '.join(f'{t} {len(r)}' for t, r in by_task.items())}; "
                f"band: 95 % stratified bootstrap (rliable, {stats.PROFILE_REPS} resamples)"
                + (f"; {outside} score(s) beyond the tau range drawn" if outside else "")
                + (f"; left out: {'; '.join(left)}" if left else ""))
        budgets = ", ".join(sorted({str(r.settings.get("budget")) for rs in by_task.values() for r in rs}))
        made.append(profile_plot(curves, taus, f"performance profile of normalized loss ({budgets} budget), "
                                 f"{n_runs} runs per baseline\n1 = that seed's tf-full, 0 = its no-comm; further "
                                 "right is better",
                                 note, out_dir / SEEDS_PROFILE))
    return made
