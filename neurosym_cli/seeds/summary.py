"""Across-seed statistics of one task: per baseline and metric the mean with its t interval and the IQM with its
bootstrap interval, the probability of improvement, their captions, CSV rows and marl-eval's JSON layout."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable, Sequence

from .. import stats
from ..errors import UserError
from .read import METHOD, PAIRS, SeedRun, check_same, metric_order

@dataclass
class Summary:
    """The across-seed statistics of one task: per row (baseline) and metric, stats.across_seeds; the training
    seeds present per row; the probability of improvement of METHOD over the others."""

    task: str
    seeds: list[int]
    rows: dict[str, dict[str, dict]]
    row_seeds: dict[str, list[int]]
    labels: dict[str, list[str]]
    improvement: list[dict]
    notes: list[str]


def order(keys: Iterable[str]) -> list[str]:
    """Rows in the paper's order (schemes.SCHEMES), other labels after their baseline."""
    from ..schemes import SCHEMES as BASELINES

    names = list(BASELINES)

    def rank(k: str) -> tuple[int, str]:
        base = max((b for b in names if k == b or k.startswith(b + "-") or
                    (k.startswith(b) and k[len(b):].isdigit())), key=len, default=None)
        return (names.index(base) if base else len(names), k)

    return sorted(keys, key=rank)


def summarize(runs: Sequence[SeedRun], mix: bool = False, reps: int = stats.REPS, seed: int = 0) -> Summary:
    """The across-seed statistics of one task's training seeds (checked for equal settings first)."""
    if not runs:
        raise UserError("no training seeds to summarize")
    notes = check_same(runs, mix)
    rows: dict[str, dict[str, dict]] = {}
    row_seeds: dict[str, list[int]] = {}
    labels: dict[str, list[str]] = {}
    for key in order({k for r in runs for k in r.entries}):
        have = [r for r in runs if key in r.entries]
        row_seeds[key] = [r.seed for r in have]
        labels[key] = [r.entries[key].label for r in have]
        rows[key] = {}
        first = have[0].entries[key].rows[0]
        for m in [m for m in metric_order(first) if all(m in r.entries[key].rows[0] for r in have)]:
            s = stats.across_seeds([r.entries[key].mean(m) for r in have], reps, seed)
            if len(have) == 1:  # one training seed: what it has is the interval over its evaluation seeds
                s["eval_ci95"] = have[0].entries[key].eval_ci(m)
                s["eval_seeds"] = len(have[0].entries[key].rows)
            rows[key][m] = s
    improvement = []
    if METHOD in rows:
        others = [b for b in PAIRS if b in rows] + [b for b in rows if b not in PAIRS and b != METHOD]
        for b in others:
            both = [r for r in runs if METHOD in r.entries and b in r.entries]
            x = [r.entries[METHOD].mean("cost") for r in runs if METHOD in r.entries]
            y = [r.entries[b].mean("cost") for r in runs if b in r.entries]
            p, lo, hi = stats.improvement_ci(x, y, True, reps, seed)
            n = (len(x), len(y))
            improvement.append({"x": METHOD, "y": b, "metric": "cost", "p": p,
                                "lo": lo if min(n) > 1 else None, "hi": hi if min(n) > 1 else None,
                                "n_x": n[0], "n_y": n[1], "paired_seeds": len(both)})
    return Summary(runs[0].task, sorted({r.seed for r in runs}), rows, row_seeds, labels, improvement, notes)


# ------------------------------------------------------------------------------------------------ formatting
def fmt_mean(s: dict, digits: int = 2) -> str:
    """'mean ± t half-width' across seeds; one seed: its value, marked as one seed."""
    if s["n"] == 1:
        return f"{s['mean']:.{digits}f} (1 seed)"
    return f"{s['mean']:.{digits}f} ± {s['ci95']:.{digits}f}"


def fmt_iqm(s: dict, digits: int = 2) -> str:
    """'IQM [lower, upper]' across seeds; '-' for one seed (no interval, and the IQM of one value is it)."""
    if s["n"] == 1:
        return "-"
    return f"{s['iqm']:.{digits}f} [{s['iqm_lo']:.{digits}f}, {s['iqm_hi']:.{digits}f}]"


def fmt_p(r: dict) -> str:
    if r["lo"] is None:
        return f"{r['p']:.2f} (1 seed: no interval)"
    return f"{r['p']:.2f} [{r['lo']:.2f}, {r['hi']:.2f}]"


def caption(n: int) -> str:
    """What every ± and [ ] of an across-seed table is."""
    if n == 1:
        return ("1 training seed: its model's mean over the evaluation seeds ± 95 % Student-t interval over those "
                "evaluation seeds (episode noise of one trained model; no interval across one training seed)")
    dof = f"{n - 1} degree{'s' if n > 2 else ''} of freedom"
    return (f"{n} training seeds, each one number (its model's mean over the evaluation seeds): mean ± 95 % "
            f"Student-t interval across training seeds ({dof}); IQM [95 % stratified bootstrap percentile interval] "
            "(rliable; with fewer than 4 seeds the IQM is the mean)")


# ------------------------------------------------------------------------------------------------ exports
def csv_rows(s: Summary) -> list[dict[str, Any]]:
    """One row per (baseline, metric): the across-seed statistics, long format."""
    out = []
    for key, metrics in s.rows.items():
        for m, st in metrics.items():
            half = st["ci95"]
            out.append({"task": s.task, "baseline": key, "labels": " ".join(sorted(set(s.labels[key]))),
                        "metric": m, "train_seeds": st["n"], "seeds": " ".join(map(str, s.row_seeds[key])),
                        "mean": st["mean"], "ci95_half": "" if half is None else half,
                        "ci95_lo": "" if half is None else st["mean"] - half,
                        "ci95_hi": "" if half is None else st["mean"] + half,
                        "iqm": st["iqm"], "iqm_lo": "" if st["iqm_lo"] is None else st["iqm_lo"],
                        "iqm_hi": "" if st["iqm_hi"] is None else st["iqm_hi"],
                        "std": "" if st["std"] is None else st["std"], "min": st["min"], "max": st["max"],
                        "eval_ci95_one_seed": st.get("eval_ci95", "")})
    return out


def improvement_rows(s: Summary) -> list[dict[str, Any]]:
    return [{"task": s.task, "x": r["x"], "y": r["y"], "metric": r["metric"], "p_x_improves_on_y": r["p"],
             "lo": "" if r["lo"] is None else r["lo"], "hi": "" if r["hi"] is None else r["hi"],
             "runs_x": r["n_x"], "runs_y": r["n_y"]} for r in s.improvement]


def step_count(budget: str) -> int:
    """The budget's oracle training rollouts (conf/budget/<name>.yaml), marl-eval's step_count of a final
    evaluation; 0 when the budget file is unknown."""
    import re
    from importlib.resources import files

    f = files("neurosym_cli.conf") / "budget" / f"{budget}.yaml"
    try:
        m = re.search(r"^train_rollouts:\s*([0-9_]+)", f.read_text(), re.M)
    except OSError:
        return 0
    return int(m.group(1).replace("_", "")) if m else 0


def marl_eval(by_task: dict[str, Sequence[SeedRun]], environment: str = "neurosym") -> dict:
    """marl-eval's raw-data layout (instadeepai/marl-eval README, 'Data Structure for Raw Experiment data'):
    environment -> task -> algorithm -> run -> {"step_1": {"step_count", metric: [...]}, "absolute_metrics":
    {metric: [...]}}. Runs are training seeds (``seed0``...); each metric's list holds one value per evaluation
    seed (its mean over that seed's episodes); there is one logging step, the final evaluation, so step_1 and
    absolute_metrics hold the same lists; step_count is the budget's oracle training rollouts. Losses stay
    lower-is-better: tell marl-eval so (negate them) before its probability of improvement."""
    out: dict = {environment: {}}
    for task, runs in by_task.items():
        algos: dict[str, dict] = {}
        for r in runs:
            steps = step_count(str(r.settings.get("budget")))
            for key, e in r.entries.items():
                vals = {m: [row[m] for row in e.rows] for m in metric_order(e.rows[0])}
                algos.setdefault(key, {})[f"seed{r.seed}"] = {"step_1": {"step_count": steps, **vals},
                                                              "absolute_metrics": vals}
        out[environment][task] = algos
    return out


