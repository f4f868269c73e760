"""`neurosym report`: aggregate the evaluations of every training seed of a (task, budget) into one table.

Reads <runs_root>/<task>/<budget>/seed*/eval/*/metrics.json, or any directory given as report_dir=PATH (a
directory of seed directories, or one experiment directory). For each baseline: the mean over training seeds of
each metric (each itself a mean over the evaluation seeds) and the spread across training seeds; with a single
training seed, the spread over its evaluation seeds. Writes report.json, report.csv and report.png next to the
seed directories, and prints the table.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..config import RunConfig
from ..plotting import figure2
from ..rollout import METRICS
from ..utils.console import console, metrics_table
from ..utils.io import ArtifactError, read_json, write_csv, write_json
from ._run import Context
from .eval import COLUMNS, ORDER


def aggregate(root: Path) -> tuple[list[tuple[str, dict]], list[str]]:
    """(label, summary) per baseline over the seed directories under ``root``, and the seeds found."""
    by_label: dict[str, list[dict]] = {}
    names: dict[str, str] = {}
    files = sorted(root.glob("seed*/eval/*/metrics.json")) or sorted(root.glob("eval/*/metrics.json"))
    seeds = sorted({f.parents[2].name for f in files})
    for f in files:
        m = read_json(f)
        by_label.setdefault(m["label"], []).append(m["summary"])
        names[m["label"]] = m["baseline"]
    rows = []
    for label, sums in by_label.items():
        out = {}
        for k in METRICS:
            means = [s[k]["mean"] for s in sums]
            n = len(means)
            mean = sum(means) / n
            std = (math.sqrt(sum((x - mean) ** 2 for x in means) / (n - 1)) if n > 1 else sums[0][k]["std"])
            out[k] = {"mean": mean, "std": std, "train_seeds": n}
        rows.append((label, out))
    rows.sort(key=lambda r: (ORDER.index(names[r[0]]) if names[r[0]] in ORDER else len(ORDER), r[0]))
    return rows, seeds


def run(cfg: RunConfig, ctx: Context) -> dict:
    root = Path(cfg.report_dir) if cfg.report_dir else Path(cfg.runs_root) / cfg.task.name / cfg.budget.name
    rows, seeds = aggregate(root)
    if not rows:
        raise ArtifactError(f"no evaluations under {root}; run `neurosym pipeline task={cfg.task.name} "
                            f"budget={cfg.budget.name}` (or `neurosym eval ...`) first")
    n = max(r[1]["cost"]["train_seeds"] for r in rows)
    spread = "std over training seeds" if n > 1 else "std over evaluation seeds (one training seed)"
    where = str(root) if cfg.report_dir else f"{cfg.task.name} ({cfg.budget.name} budget)"
    title = f"{where}, {len(seeds)} training seed(s): mean ± {spread}"
    write_json(root / "report.json", {"task": cfg.task.name, "budget": cfg.budget.name, "seeds": seeds,
                                      "baselines": {label: s for label, s in rows}})
    write_csv(root / "report.csv", [{"baseline": label, **{f"{k}_{x}": s[k][x] for k in METRICS
                                                           for x in ("mean", "std")}} for label, s in rows])
    png = figure2(rows, title.replace(": ", ":\n"), root / "report.png")
    console.print(metrics_table(title, rows, COLUMNS))
    console.print(f"wrote {root / 'report.json'}, {root / 'report.csv'}, {png}")
    return {"report": str(root / "report.json")}
