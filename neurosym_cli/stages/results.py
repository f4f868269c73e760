"""Evaluations read back: every baseline evaluated in one run directory, or aggregated over the training seeds of
a (task, budget), in the paper's order (``schemes.SCHEMES``), as tables and Figure-2-style plots."""

from __future__ import annotations

import math
from pathlib import Path

from .. import schemes
from ..config import RunConfig
from ..plotting import figure2, pareto_plot, training_curves
from ..rollout import METRICS
from ..utils.console import console, log, metrics_table
from ..utils.io import ArtifactError, read_json, write_csv, write_json

COLUMNS = [("cost", "loss"), ("max_in", "max in-deg"), ("max_out", "max out-deg"), ("mean_degree", "mean deg"),
           ("collisions", "collisions")]
"""(metric, column title) of every results table"""

Rows = list[tuple[str, dict]]
"""(label, summary) per evaluated baseline; a summary maps each metric to its mean, std, ..."""


def _metrics(path: Path) -> dict:
    """One metrics.json, checked for the fields the tables read."""
    m = read_json(path)
    if not (isinstance(m, dict) and isinstance(m.get("label"), str) and isinstance(m.get("baseline"), str)
            and isinstance(m.get("summary"), dict) and all(isinstance(m["summary"].get(k), dict) for k in METRICS)):
        raise ArtifactError(f"{path} is not an evaluation written by `neurosym eval`; delete it and evaluate again")
    return m


def collect(exp_dir: Path) -> Rows:
    """Every baseline evaluated in an experiment directory, in the paper's order."""
    found = [_metrics(f) for f in sorted((Path(exp_dir) / "eval").glob("*/metrics.json"))]
    found.sort(key=lambda m: (schemes.rank(m["baseline"]), m["label"]))
    return [(m["label"], m["summary"]) for m in found]


def aggregate(root: Path) -> tuple[Rows, list[str]]:
    """(label, summary) per baseline over the seed directories under ``root`` (or of ``root`` itself): the mean
    over training seeds of each metric and the spread across them; with one training seed, its spread over
    evaluation seeds. Also the seed directories found."""
    by_label: dict[str, list[dict]] = {}
    names: dict[str, str] = {}
    files = sorted(root.glob("seed*/eval/*/metrics.json")) or sorted(root.glob("eval/*/metrics.json"))
    seeds = sorted({f.parents[2].name for f in files})
    for f in files:
        m = _metrics(f)
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
    rows.sort(key=lambda r: (schemes.rank(names[r[0]]), r[0]))
    return rows, seeds


def histories(root: Path) -> list[tuple[str, str, bool, list[list[tuple[float, float]]]]]:
    """Training histories under ``root`` (its seed directories, or root itself): per model directory, its label,
    baseline, whether it is a retraining, and one [(rollouts, loss)] per training seed, in the paper's order."""
    import csv

    files = sorted(root.glob("seed*/train/*/history.csv")) or sorted(root.glob("train/*/history.csv"))
    runs: dict[str, list[list[tuple[float, float]]]] = {}
    for f in files:
        try:
            with open(f, newline="") as fh:
                h = [(float(r["rollouts"]), float(r["loss"])) for r in csv.DictReader(fh)]
        except (OSError, KeyError, ValueError, TypeError):
            log.warning("skipping %s: not a training history written by neurosym", f)
            continue
        if h:
            runs.setdefault(f.parent.name, []).append(h)
    out = []
    for model, hs in runs.items():
        baseline, retrained = schemes.model_baseline(model)
        label = "tf-full (the oracle)" if model == "oracle" else (
            f"{baseline} {model.removeprefix('retrained-')}" if retrained else model)
        out.append((label, baseline, retrained, hs))
    out.sort(key=lambda r: (r[2], schemes.rank(r[1]), r[0]))
    return out


def write_curves(root: Path, head: str, path: Path) -> Path | None:
    """Training curves of every model under ``root`` as a PNG (None when nothing was trained there)."""
    runs = histories(root)
    return training_curves(runs, head, path) if runs else None


def write_pareto(rows: Rows, root: Path, head: str, plot: bool = True) -> tuple[Path, Path | None]:
    """pareto.csv and pareto.png: loss against max degree of every row, the non-dominated set, and the area it
    dominates up to the reference point (1.05 x the largest degree and the largest loss found here)."""
    from ..utils.pareto import dominated_area, pareto_front

    pts = [(label, s["max_degree"]["mean"], s["cost"]["mean"]) for label, s in rows]
    xy = [(x, y) for _, x, y in pts]
    front = pareto_front(xy)
    ref = (1.05 * max(x for x, _ in xy) + 1e-9, 1.05 * max(y for _, y in xy))
    area = dominated_area([xy[i] for i in front], ref)
    csv_path = root / "pareto.csv"
    write_csv(csv_path, [{"label": label, "max_degree": x, "loss": y, "non_dominated": int(k in front),
                          "ref_max_degree": ref[0], "ref_loss": ref[1], "dominated_area": area}
                         for k, (label, x, y) in enumerate(pts)])
    png = pareto_plot(pts, front, ref, area, head.replace(": ", ":\n") + "\nloss against degree: the lower "
                      "left is better", root / "pareto.png") if plot else None
    log.info("non-dominated (loss, max degree): %s; dominated area %.4g up to %s",
             ", ".join(pts[i][0] for i in front), area, tuple(round(v, 4) for v in ref))
    return csv_path, png


def title(cfg: RunConfig) -> str:
    return (f"{cfg.task.name} ({cfg.budget.name} budget, train seed {cfg.seed}): "
            f"mean ± std over {cfg.budget.eval_seeds} eval seeds")


def write_figure(cfg: RunConfig) -> Path:
    """Figure-2-style PNG of every baseline evaluated in this experiment directory (and the training curves of
    its models beside it, curves.png)."""
    write_curves(Path(cfg.exp_dir), f"{cfg.task.name} ({cfg.budget.name} budget, train seed {cfg.seed}): "
                 "training curves", Path(cfg.exp_dir) / "eval" / "curves.png")
    return figure2(collect(Path(cfg.exp_dir)), title(cfg).replace(": ", ":\n"),
                   Path(cfg.exp_dir) / "eval" / "figure2.png")


def print_table(cfg: RunConfig) -> None:
    """The results table of every baseline evaluated in this experiment directory, and its plot."""
    console.print(metrics_table(title(cfg), collect(Path(cfg.exp_dir)), COLUMNS))
    if cfg.plots:
        png = write_figure(cfg)
        console.print(f"plot of every baseline evaluated here: {png} (training curves: {png.with_name('curves.png')})")


def report(cfg: RunConfig) -> dict:
    """`neurosym report`: the evaluations of every training seed of a (task, budget), or of ``report_dir``, as one
    table; writes report.json, report.csv and report.png beside the seed directories."""
    root = Path(cfg.report_dir) if cfg.report_dir else Path(cfg.exp_dir).parent  # <runs_root>/<task>/<budget>
    rows, seeds = aggregate(root)
    if not rows:
        raise ArtifactError(f"no evaluations under {root}; run `neurosym pipeline task={cfg.task.name} "
                            f"budget={cfg.budget.name}` (or `neurosym eval ...`) first")
    n = max(r[1]["cost"]["train_seeds"] for r in rows)
    spread = "std over training seeds" if n > 1 else "std over evaluation seeds (one training seed)"
    where = str(root) if cfg.report_dir else f"{cfg.task.name} ({cfg.budget.name} budget)"
    head = f"{where}, {len(seeds)} training seed{'s' if len(seeds) > 1 else ''}: mean ± {spread}"
    console.print(metrics_table(head, rows, COLUMNS))
    try:
        write_json(root / "report.json", {"task": cfg.task.name, "budget": cfg.budget.name, "seeds": seeds,
                                          "baselines": {label: s for label, s in rows}})
        write_csv(root / "report.csv", [{"baseline": label, **{f"{k}_{x}": s[k][x] for k in METRICS
                                                               for x in ("mean", "std")}} for label, s in rows])
        pareto_csv, pareto_png = write_pareto(rows, root, head, cfg.plots)
        png = figure2(rows, head.replace(": ", ":\n"), root / "report.png") if cfg.plots else None
        plural = "s" if len(seeds) > 1 else ""
        curves = write_curves(root, f"{where}: training curves, {len(seeds)} training seed{plural}",
                              root / "report_curves.png") if cfg.plots else None
    except (ArtifactError, OSError) as e:  # an archived, read-only directory: the table above is the report
        log.warning("report files not written (%s); the table above is the report", e)
        return {"report": None}
    console.print(f"wrote {root / 'report.json'}, {root / 'report.csv'}, {pareto_csv}"
                  + "".join(f", {f}" for f in (png, pareto_png, curves) if f))
    figures = sorted(root.glob("seed*/figures/*.png")) or sorted(root.glob("figures/*.png"))
    if figures:  # drawn per training seed by the pipeline or `neurosym figures`
        console.print("figures of whom agents talk to: " + ", ".join(str(f) for f in figures))
    return {"report": str(root / "report.json")}
