"""Evaluations read back: every baseline evaluated in one run directory, or aggregated over the training seeds of
a (task, budget), in the paper's order (``schemes.SCHEMES``), as tables and Figure-2-style plots."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Iterable

from .. import schemes
from ..config import RunConfig
from ..baselines import run_args
from ..degrees import BANDWIDTH, BANDWIDTH_LEGEND, LEGEND, NAMES
from ..run import RunDir, pipeline_command, show_command
from ..run.layout import (FIGURES, IMPROVEMENT_CSV, PARETO_CSV, PARETO_PNG, REPORT_CSV, REPORT_CURVES, REPORT_JSON,
                          REPORT_MARL_EVAL, REPORT_PNG, SEED_PREFIX, RunsRoot, history_files, metrics_files)
from ..seeds.read import SHARED as METRICS  # every evaluation's metrics, named without torch
from ..seeds.read import metric_order
from ..stats import mean_ci
from ..utils.console import console, log, metrics_table
from ..utils.io import ArtifactError, read_json, write_csv, write_json
from .guard import PROGRAM_PREFIXES, communication_guard

COLUMNS = [("cost", "loss"), *((m, NAMES[m]) for m in ("max_in", "max_out", "max_degree", "mean_degree", *BANDWIDTH)),
           ("collisions", "collisions")]
"""(metric, column title) of every results table; any other metric the evaluations hold follows (columns). An
evaluation without one shows '-' (bits and link share: one written before them; collisions: a task without them)"""

CAPTION = f"{LEGEND}\n{BANDWIDTH_LEGEND}"
"""the lines under every results table: what each degree and bandwidth column is"""


def columns(metrics: Iterable[str]) -> list[tuple[str, str]]:
    """(metric, column title) of a table whose rows hold ``metrics``: COLUMNS, then every other metric present (a
    task's own, ``Task.metrics``, or a scheme's), titled by its key, in the order first met."""
    known = {m for m, _ in COLUMNS}
    return COLUMNS + [(m, NAMES.get(m, m)) for m in metric_order(metrics) if m not in known]

Rows = list[tuple[str, dict]]
"""(label, summary) per evaluated baseline; a summary maps each metric to its mean, std, ..."""


def _evaluation(m: object) -> bool:
    """Whether a record is a metrics.json of `neurosym eval`: the fields the tables read."""
    return (isinstance(m, dict) and isinstance(m.get("label"), str) and isinstance(m.get("baseline"), str)
            and isinstance(m.get("summary"), dict) and all(
                isinstance(m["summary"].get(k), dict) and isinstance(m["summary"][k].get("mean"), (int, float))
                for k in METRICS))


def _metrics(path: Path, remake: str) -> dict:
    """One metrics.json, checked for the fields the tables read and for a nan or inf in them (a hand-edited or
    foreign file: `neurosym eval` writes none); ``remake``: the command that writes it again."""
    from ..seeds.read import NOT_A_RESULT, non_finite

    m = read_json(path, remake, _evaluation)
    bad = next((f"summary.{k}.{f} is {v}" for k, st in m["summary"].items() if isinstance(st, dict)
                for f, v in st.items() if isinstance(v, float) and not math.isfinite(v)), None)
    bad = bad or non_finite(m.get("per_seed") if isinstance(m.get("per_seed"), list) else [])
    if bad:
        raise ArtifactError(f"{path}: {bad}, {NOT_A_RESULT}: delete it and run `{remake}`, which writes it again")
    return m


def _eval_interval(m: dict) -> dict:
    """The summary with ``ci95`` recomputed from the per-seed rows (t, not the 1.96 that older files hold)."""
    rows = m.get("per_seed") or []
    out = {}
    for k, s in m["summary"].items():
        vals = [r[k] for r in rows if isinstance(r, dict) and isinstance(r.get(k), (int, float))]
        out[k] = {**s, "ci95": mean_ci(vals)[1] if len(vals) > 1 else 0.0} if isinstance(s, dict) else s
    return out


def collect(exp_dir: Path, remake: str = "neurosym pipeline") -> Rows:
    """Every baseline evaluated in an experiment directory, in the paper's order (summaries over its evaluation
    seeds: mean, std, ci95 = the 95 % t half-width); ``remake``: the command that evaluates them again."""
    found = [_metrics(f, remake) for f in metrics_files(exp_dir)]
    found.sort(key=lambda m: (schemes.rank(m["baseline"]), m["label"]))
    return [(m["label"], _eval_interval(m)) for m in found]


def histories(root: Path) -> list[tuple[str, str, bool, list[list[tuple[float, float]]]]]:
    """Training histories under ``root`` (its seed directories, or root itself): per model directory, its label,
    baseline, whether it is a retraining, and one [(rollouts, loss)] per training seed, in the paper's order."""
    import csv

    files = history_files(root)
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
    from ..plotting import training_curves  # matplotlib only where a figure is drawn

    runs = histories(root)
    return training_curves(runs, head, path) if runs else None


def write_pareto(rows: Rows, root: Path, head: str, plot: bool = True) -> tuple[Path, Path | None]:
    """pareto.csv and pareto.png: loss against max degree of every row, the non-dominated set, and the area it
    dominates up to the reference point (1.05 x the largest degree and the largest loss found here)."""
    from ..plotting import pareto_plot
    from ..utils.pareto import dominated_area, pareto_front

    pts = [(label, s["max_degree"]["mean"], s["cost"]["mean"]) for label, s in rows]
    xy = [(x, y) for _, x, y in pts]
    front = pareto_front(xy)
    ref = (1.05 * max(x for x, _ in xy) + 1e-9, 1.05 * max(y for _, y in xy))
    area = dominated_area([xy[i] for i in front], ref)
    csv_path = root / PARETO_CSV
    write_csv(csv_path, [{"label": label, "max_degree": x, "loss": y, "non_dominated": int(k in front),
                          "ref_max_degree": ref[0], "ref_loss": ref[1], "dominated_area": area}
                         for k, (label, x, y) in enumerate(pts)])
    png = pareto_plot(pts, front, ref, area, head.replace(": ", ":\n") + f"\nloss against {NAMES['max_degree']}: "
                      "the lower left is better", root / PARETO_PNG) if plot else None
    shown = sorted(front, key=lambda i: (pts[i][2], pts[i][1]))  # lowest loss first
    log.info("non-dominated (loss, %s), lowest loss first: %s; dominated area %.4g up to the reference point "
             "(loss %.4g, %s %.4g)", NAMES["max_degree"],
             ", ".join(f"{pts[i][0]} ({pts[i][2]:.3f}, {pts[i][1]:.3f})" for i in shown), area, ref[1],
             NAMES["max_degree"], ref[0])
    return csv_path, png


def title(cfg: RunConfig) -> str:
    return (f"{cfg.task.name} ({cfg.budget.name} budget, train seed {cfg.seed}): mean ± 95 % Student-t interval "
            f"over {cfg.budget.eval_seeds} evaluation seeds of each trained model (one training seed)")


def write_figure(cfg: RunConfig) -> Path:
    """Figure-2-style PNG of every baseline evaluated in this experiment directory (and the training curves of
    its models beside it, curves.png)."""
    from ..plotting import figure2
    from ..tasks.base import cost_words

    write_curves(Path(cfg.exp_dir), f"{cfg.task.name} ({cfg.budget.name} budget, train seed {cfg.seed}): "
                 "training curves", RunDir(cfg).curves_file)
    return figure2(collect(Path(cfg.exp_dir), pipeline_command(cfg)), title(cfg).replace(": ", ":\n"),
                   RunDir(cfg).figure2_file, err="ci95", cost_words=cost_words(cfg.task))


def _guard_inputs(cfg: RunConfig, program: str) -> tuple[list[str], dict[str, dict[int, float]]]:
    """The guard's inputs from this run directory: the labels of the run's own program baselines (under
    ``program``, "" for the searched one; prog-retrained's first) and tf-full's and no-comm's loss per evaluation
    seed (their metrics.json's per-seed rows, for the paired rule)."""
    from ..config import UserError

    labels = []
    for name in PROGRAM_PREFIXES:
        try:
            labels.append(RunDir(dataclasses.replace(cfg, baseline=schemes.get(name), program=program)).label)
        except (UserError, OSError):  # a program file gone since its evaluation: no label of this run to judge
            continue
    per_seed = {}
    for label in ("tf-full", "no-comm"):
        f = RunDir(cfg).metrics_of(label)
        if f.exists():
            rows = _metrics(f, pipeline_command(cfg)).get("per_seed") or []
            per_seed[label] = {r["seed"]: float(r["cost"]) for r in rows if isinstance(r, dict)
                               and isinstance(r.get("seed"), int) and isinstance(r.get("cost"), (int, float))}
    return labels, per_seed


def print_table(cfg: RunConfig, *, program: str | None = None) -> None:
    """The results table of every baseline evaluated in this experiment directory, and its plot; the guard's line
    under it judges the run's own program (``program``: the file prog and prog-retrained ran under, cfg.program by
    default, "" for the searched one)."""
    rows = collect(Path(cfg.exp_dir), pipeline_command(cfg))
    console.print(metrics_table(title(cfg), rows, columns(m for _, s in rows for m in s), err="ci95",
                                caption=CAPTION))
    labels, per_seed = _guard_inputs(cfg, cfg.program if program is None else program)
    line = communication_guard(rows, labels=labels, rerun=f"neurosym synth baseline=prog {run_args(cfg)}",
                               show=show_command(dataclasses.replace(cfg, baseline=schemes.get("prog"))),
                               per_seed=per_seed,
                               settings={"synth.front": cfg.synth.front, "synth.search": cfg.synth.search,
                                         "synth.objective": cfg.synth.objective})
    if line:
        log.warning(line)
    if cfg.plots:
        png = write_figure(cfg)
        console.print(f"plot of every baseline evaluated here: {png} (training curves: {RunDir(cfg).curves_file})")


def across_table(s, digits: int = 3):
    """The rich table of one task's across-seed statistics (seeds.Summary); its caption says what every ± is."""
    from rich.table import Table

    from .. import seeds

    n = len(s.seeds)
    t = Table(title=f"{s.task}: {n} training seed{'s' if n > 1 else ''} ({', '.join(map(str, s.seeds))})",
              caption=f"{seeds.caption(n)}\n{CAPTION}", header_style="bold", caption_justify="left")
    t.add_column("baseline")
    t.add_column("n seeds", justify="right")
    cols = columns(k for m in s.rows.values() for k in m)
    for _, head in cols:
        t.add_column(head, justify="right")
    if n > 1:
        t.add_column("loss IQM [bootstrap 95 %]", justify="right")
    for key, m in s.rows.items():
        one = m["cost"]["n"] == 1
        cells = [("-" if k not in m else f"{m[k]['mean']:.{digits}f} ± {m[k]['eval_ci95']:.{digits}f}"
                  if one and n == 1 else seeds.fmt_mean(m[k], digits)) for k, _ in cols]
        t.add_row(key, str(m["cost"]["n"]), *cells, *([seeds.fmt_iqm(m["cost"], digits)] if n > 1 else []))
    return t


def improvement_table(s):
    """P(prog-retrained improves on each other baseline) on the loss, with its bootstrap interval."""
    from rich.table import Table

    from .. import seeds

    t = Table(title=f"{s.task}: probability of improvement on the loss over training seeds",
              caption="P(X improves on Y) = share of (seed of X, seed of Y) pairs where X's loss is lower, ties 1/2 "
                      "(rliable's Mann-Whitney form); [95 % stratified independent bootstrap percentile interval]; "
                      "0.5 = no difference", header_style="bold", caption_justify="left")
    for c in ("X", "Y", "P(X improves on Y)", "seeds X / Y"):
        t.add_column(c, justify="left" if c in ("X", "Y") else "right")
    for r in s.improvement:
        t.add_row(r["x"], r["y"], seeds.fmt_p(r), f"{r['n_x']} / {r['n_y']}")
    return t


def write_across(by_task: dict, summaries: dict, out: Path, head: str, plots: bool) -> list[Path]:
    """report.json (per task the across-seed statistics), report.csv (long: task, baseline, metric, ...),
    improvement.csv, report_marl_eval.json (marl-eval's raw layout) and, with plots, the across-seed figures."""
    from .. import seeds

    files = [out / REPORT_JSON, out / REPORT_CSV, out / IMPROVEMENT_CSV, out / REPORT_MARL_EVAL]
    write_json(files[0], {"convention": {"mean ± ci95": "95 % Student-t interval across training seeds",
                                         "iqm [iqm_lo, iqm_hi]": "25 % trimmed mean, 95 % stratified bootstrap "
                                                                 "percentile interval (rliable)",
                                         "eval_ci95": "one training seed only: 95 % t-interval over the "
                                                      "evaluation seeds of that one model"},
                          "tasks": {t: {"seeds": s.seeds, "notes": s.notes, "baselines": {
                              k: {**m, "train_seeds": m["cost"]["n"], "seed_list": s.row_seeds[k],
                                  "labels": s.labels[k]} for k, m in s.rows.items()},
                              "improvement": s.improvement} for t, s in summaries.items()}})
    write_csv(files[1], [row for s in summaries.values() for row in seeds.csv_rows(s)])
    write_csv(files[2], [row for s in summaries.values() for row in seeds.improvement_rows(s)])  # empty: none
    write_json(files[3], seeds.marl_eval(by_task))
    if plots:
        files += seeds.draw(by_task, out, mix=True)  # the settings were checked (or mixing asked) above
    return files


def report(cfg: RunConfig) -> dict:
    """`neurosym report`: across the training seeds of a (task, budget) (<runs_root>/<task>/<budget>/seed*), of
    ``report_dir``, or of the seed files in ``report.seed_files``: per baseline and metric the mean ± 95 % t-interval
    across seeds and the IQM with its bootstrap interval, the probability of improvement of prog-retrained over
    the others; tables on screen, CSV, JSON and marl-eval JSON beside them (figures with plots=true). Reads only;
    writes only its report files."""
    from .. import seeds
    from ..plotting import figure2
    from ..tasks.base import cost_words

    rc = cfg.report
    if rc.seed_files:
        src = Path(rc.seed_files)
        files = sorted(src.glob("*.json")) if src.is_dir() else []
        if not files:
            raise ArtifactError(f"no seed files in {src}; benchmarks/run_seeds.py writes them "
                                "(docs/results/seeds/<task>-seed<S>.json)")
        by_task = seeds.from_seed_files(files)
        out = Path(cfg.report_dir) if cfg.report_dir else src / "report"
        head = f"seed files of {src}"
    else:
        root = Path(cfg.report_dir) if cfg.report_dir else Path(cfg.exp_dir).parent  # <runs_root>/<task>/<budget>
        runs = seeds.from_runs_root(root)
        if not runs:
            raise ArtifactError(f"no evaluations under {root}; {_what_makes(cfg, root)}")
        task = runs[0].task or cfg.task.name
        by_task = {task: runs}
        out = root
        head = str(root) if cfg.report_dir else f"{cfg.task.name}, {cfg.budget.name} budget"
    summaries = {t: seeds.summarize(r, rc.mix, rc.reps, rc.bootstrap_seed) for t, r in by_task.items()}
    for s in summaries.values():
        console.print(across_table(s))
        if any(r["lo"] is not None for r in s.improvement):
            console.print(improvement_table(s))
        elif s.improvement:
            console.print(f"{s.task}: probability of improvement not shown: one training seed per baseline (it would "
                          "be 0, 1/2 or 1, one comparison; improvement.csv has it)")
        for line in s.notes:
            console.print(f"[yellow]mixed (report.mix=true):[/] {line}")
    try:
        files = write_across(by_task, summaries, out, head, cfg.plots)
        if not rc.seed_files:
            rows = _rows_for_figures(summaries[next(iter(summaries))])
            pareto_csv, pareto_png = write_pareto(rows, out, head, cfg.plots)
            files += [pareto_csv] + ([pareto_png] if pareto_png else [])
            if cfg.plots:
                n = len(by_task[next(iter(by_task))])
                what = ("mean ± 95 % t-interval across training seeds" if n > 1 else
                        "1 training seed: mean ± 95 % t-interval over its evaluation seeds")
                words = cost_words(cfg.task) if task == cfg.task.name else ""  # another task's runs: unknown
                files.append(figure2(rows, f"{head}, {n} training seed{'s' if n > 1 else ''}:\n{what}",
                                     out / REPORT_PNG, err="err", cost_words=words))
                curves = write_curves(out, f"{head}: training curves, {n} training seed{'s' if n > 1 else ''}",
                                      out / REPORT_CURVES)
                files += [curves] if curves else []
    except (ArtifactError, OSError) as e:  # an archived, read-only directory: the tables above are the report
        log.warning("report files not written (%s); the tables above are the report", e)
        return {"report": None}
    console.print("wrote " + ", ".join(str(f) for f in files))
    if not rc.seed_files:
        figures = sorted(out.glob(f"{SEED_PREFIX}*/{FIGURES}/*.png")) or sorted(out.glob(f"{FIGURES}/*.png"))
        if figures:  # drawn per training seed by the pipeline or `neurosym figures`
            console.print("figures of whom agents talk to: " + ", ".join(str(f) for f in figures))
    return {"report": str(out / REPORT_JSON)}


def _what_makes(cfg: RunConfig, root: Path) -> str:
    """What to run when ``root`` holds no evaluations: the pipeline of the (task, budget[, seed]) that ``root``
    names (report_dir=<runs root>/<task>[-fail<p>]/<budget>[/seed<k>], any runs root), else where report_dir must
    point."""
    import os
    import shlex
    from importlib.resources import files

    from ..baselines import run_args
    from ..tasks.registry import task_choices

    if not cfg.report_dir:
        make = f"run `neurosym pipeline {run_args(cfg)}` (or `neurosym eval ...`) first"
        others = _reports_here(cfg)
        if not others:
            return make
        return ("the runs root holds others: " + ", ".join(f"`{line}`" for line in others[:3])
                + (f" and {len(others) - 3} more" if len(others) > 3 else "")
                + f"; for {cfg.task.name} ({cfg.budget.name} budget) {make}")
    path = root.absolute()
    seed = RunsRoot.parse_seed_dir(path.name)
    run = path.parent if seed is not None else path  # <runs root>/<task>/<budget>
    task, fail = RunsRoot.parse_task_dir(run.parent.name)
    if task in task_choices() and (files("neurosym_cli.conf") / "budget" / f"{run.name}.yaml").is_file():
        runs_root = run.parent.parent
        same = runs_root.resolve() == Path(os.environ.get("NEUROSYM_RUNS", "outputs")).resolve()
        line = (f"neurosym pipeline task={task} budget={run.name}" + (f" seed={seed}" if seed is not None else "")
                + (f" task.link_failure={fail}" if fail else "")
                + ("" if same else " " + shlex.quote(f"runs_root={runs_root}")))
        return f"run `{line}` (or `neurosym eval ...`) first"
    return ("report_dir= names a directory of run directories (<runs_root>/<task>/<budget>, holding seed<k>/eval/), "
            "or one seed<k> directory of it; `neurosym pipeline` writes their evaluations")


def _reports_here(cfg: RunConfig) -> list[str]:
    """The `neurosym report` line of every (task, budget) that holds evaluations in ``cfg``'s runs root
    (<runs_root>/<task>[-fail<p>]/<budget>/seed<k>/eval/<label>/metrics.json), in name order: what a bare
    `neurosym report` of the default task should point at instead of running that task."""
    from ..baselines import runs_root_arg

    lines = []
    for task_dir, budget in RunsRoot(Path(cfg.runs_root)).runs_evaluated():
        task, fail = RunsRoot.parse_task_dir(task_dir)
        lines.append(f"neurosym report task={task} budget={budget}" + (f" task.link_failure={fail}" if fail else "")
                     + runs_root_arg(cfg))
    return lines


def _rows_for_figures(s) -> Rows:
    """(baseline, summary) rows with ``err`` = the across-seed t half-width (one seed: the evaluation-seed one)."""
    rows = []
    for key, m in s.rows.items():
        rows.append((key, {k: {"mean": v["mean"], "err": v["ci95"] if v["n"] > 1 else v["eval_ci95"]}
                           for k, v in m.items()}))
    return rows
