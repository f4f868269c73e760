"""Training seeds as the runs: the evaluations of one task over its training seeds, and their statistics.

Read from run directories (``<root>/seed*/eval/*/metrics.json``, what `neurosym pipeline -m seed=0,1,2` leaves) or
from the committed seed files (``docs/results/seeds/<task>-seed<S>.json``, written by benchmarks/run_seeds.py).
Per baseline and metric, each training seed contributes ONE number, its model's mean over the evaluation seeds;
across those numbers: the mean with its Student-t 95 % interval and the IQM with its stratified bootstrap interval
(stats.py, rliable's definitions); per pair of baselines the probability of improvement on the loss. A single
training seed is reported as such: no interval across one seed. Seeds whose settings differ (budget, task, K,
lambda, features, search settings...) are refused, naming the first differing key, unless mixing is asked for;
K, lambda, features and search settings picked per seed by `neurosym select` are the method's outcome and may
differ. stdlib and numpy only (no torch): the results page is rendered from these.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Sequence

from . import stats
from .errors import ConfigError, UserError
from .utils.io import ArtifactError, check_inside

SHARED = ("cost", "max_in", "max_out", "max_degree", "mean_degree")
"""the metrics every evaluation has (rollout.METRICS, named here so that reading results needs no torch)"""
METRICS = SHARED + ("collisions",)
"""what the tables report: the shared metrics, then the paper tasks' own (a task without it reports without it)"""

METHOD = "prog-retrained"
"""the baseline whose probability of improvement over every other one is reported"""

PAIRS = ("tf-full", "dist", "no-comm", "expo")
"""the comparisons of METHOD named first (the others present follow)"""

IGNORED = ("cmd", "seed", "exp_dir", "runs_root", "report_dir", "report", "device", "threads", "progress", "plots",
           "logger", "overwrite", "baselines", "episode", "render", "stress", "select.jobs", "rl.jobs", "selected",
           "baseline", "program_file")
"""config keys (and prefixes) that do not change a result, or that name the baseline rather than the run"""

PICKED = ("rules", "lam", "features", "synth")
"""what `neurosym select` chooses per training seed (K, lambda, features, search settings): allowed to differ"""


@dataclass
class Entry:
    """One baseline of one training seed: its evaluation label, per-evaluation-seed rows and settings."""

    label: str
    rows: list[dict[str, float]]
    settings: dict[str, Any] = field(default_factory=dict)

    def mean(self, metric: str) -> float:
        """The model's mean over its evaluation seeds."""
        return sum(r[metric] for r in self.rows) / len(self.rows)

    def eval_ci(self, metric: str) -> float:
        """Half-width of the 95 % t-interval over the evaluation seeds of this ONE model (inf for one seed)."""
        return stats.mean_ci([r[metric] for r in self.rows])[1]


@dataclass
class SeedRun:
    """One training seed of a task: where it was read from, its run-level settings, its pick and its baselines."""

    task: str
    seed: int
    source: str
    settings: dict[str, Any]
    pick: dict[str, Any] | None
    entries: dict[str, Entry]


def flatten(d: Any, prefix: str = "") -> dict[str, Any]:
    """Nested dicts as dotted keys -> leaf values (lists kept whole)."""
    if not isinstance(d, dict):
        return {prefix: d}
    out: dict[str, Any] = {}
    for k, v in d.items():
        out.update(flatten(v, f"{prefix}{k}." if isinstance(v, dict) else f"{prefix}{k}"))
    return out


def _ignored(key: str, picked: bool) -> bool:
    names = IGNORED + (PICKED if picked else ())
    return any(key == n or key.startswith(n + ".") for n in names)


def _key_of(baseline: str, found: list[tuple[str, dict]], pick: dict | None, label: str, config: dict) -> str:
    """The row of an evaluation: its baseline when it is the seed's only evaluation of that baseline (or the only
    one under the seed's pick), else its own label (a K sweep stays one row per K)."""
    if len(found) == 1:
        return baseline
    if pick and sum(all(c.get(k) == pick.get(k) for k in ("rules", "lam", "features")) for _, c in found) == 1 \
            and all(config.get(k) == pick.get(k) for k in ("rules", "lam", "features")):
        return baseline
    return label


def _rows(per_seed: Any, where: str) -> list[dict[str, float]]:
    if not (isinstance(per_seed, list) and per_seed
            and all(isinstance(r, dict) and all(isinstance(r.get(m), (int, float)) for m in SHARED)
                    for r in per_seed)):
        raise ArtifactError(f"{where} has no per-evaluation-seed rows with {', '.join(SHARED)}; evaluate it again")
    return [{m: float(r[m]) for m in METRICS if isinstance(r.get(m), (int, float))} | {"seed": r.get("seed")}
            for r in per_seed]


def from_run_dir(seed_dir: Path, task: str = "") -> SeedRun | None:
    """The evaluations of one seed directory (None when it has none)."""
    files = sorted(Path(seed_dir).glob("eval/*/metrics.json"))
    if not files:
        return None
    pick = None
    sel = Path(seed_dir) / "select" / "selected.json"
    if sel.exists():
        try:
            rec = json.loads(sel.read_text())
            pick = {k: rec[k] for k in ("rules", "lam", "features")}
        except (OSError, ValueError, KeyError, TypeError):
            raise ArtifactError(f"{sel} is not a selection written by `neurosym select`; run it again") from None
    raw = []
    for f in files:
        try:
            m = json.loads(f.read_text())
            raw.append((f, m["baseline"], m["label"], m.get("config") or {}, m["per_seed"]))
        except (OSError, ValueError, KeyError, TypeError):
            raise ArtifactError(f"{f} is not an evaluation written by `neurosym eval`; delete it and evaluate again") \
                from None
    by_baseline: dict[str, list[tuple[str, dict]]] = {}
    for _, b, label, c, _ in raw:
        by_baseline.setdefault(b, []).append((label, c))
    entries: dict[str, Entry] = {}
    settings: dict[str, Any] = {}
    seed = None
    for f, b, label, c, per_seed in raw:
        key = _key_of(b, by_baseline[b], pick, label, c)
        picked = bool(c.get("selected")) or (pick is not None and all(c.get(k) == pick[k] for k in pick))
        flat = {"picked by select": picked, **{k: v for k, v in flatten(c).items() if not _ignored(k, picked)}}
        entries[key] = Entry(label, _rows(per_seed, str(f)), flat)
        seed = c.get("seed", seed)
        task = task or (c.get("task") or {}).get("name", "")
        settings.setdefault("budget", (c.get("budget") or {}).get("name"))
    name = Path(seed_dir).name
    if seed is None:
        seed = int(name[4:]) if name.startswith("seed") and name[4:].isdigit() else 0
    return SeedRun(task, int(seed), str(seed_dir), settings, pick, entries)


def from_runs_root(root: Path) -> list[SeedRun]:
    """Every seed directory under ``root`` (``root/seed*``), or ``root`` itself when it is one."""
    dirs = sorted((d for d in Path(root).glob("seed*") if d.is_dir()), key=lambda d: (len(d.name), d.name))
    runs = [r for r in (from_run_dir(d) for d in dirs) if r is not None]
    if not runs:
        one = from_run_dir(Path(root))
        runs = [one] if one else []
    return runs


def from_seed_file(path: Path) -> SeedRun:
    """One committed seed file (benchmarks/run_seeds.py's ``collect``)."""
    try:
        r = json.loads(Path(path).read_text())
        entries = {b: Entry(e["label"], _rows(e["per_seed"], f"{path} ({b})"), {})
                   for b, e in r["baselines"].items()}
        sel = r.get("selected") or {}
        grid = sorted({(p.get("lam"), p.get("rules"), p.get("features")) for p in r.get("selection") or []},
                      key=str)
        settings = {"budget": r["budget"], "cpu_kernels": (r.get("machine") or {}).get("cpu_kernels"),
                    "select.grid": [list(g) for g in grid], "select.val_seeds": sel.get("val_seeds"),
                    **{f"synth.{k}": v for k, v in (sel.get("synth") or {}).items()
                       if k not in ("coarse", "patience")}}  # coarse and patience: the pick's search schedule
        return SeedRun(r["task"], int(r["seed"]), str(path), settings, r.get("pick"), entries)
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as e:
        raise ArtifactError(f"{path} is not a seed file written by benchmarks/run_seeds.py ({type(e).__name__}: {e})") \
            from None


def from_seed_files(paths: Iterable[Path]) -> dict[str, list[SeedRun]]:
    """Seed files grouped by task, each task's runs in seed order."""
    out: dict[str, list[SeedRun]] = {}
    for p in sorted(paths):
        r = from_seed_file(p)
        out.setdefault(r.task, []).append(r)
    for runs in out.values():
        runs.sort(key=lambda r: r.seed)
    return out


def _show(v: Any) -> str:
    s = json.dumps(v) if not isinstance(v, str) else v
    return s if len(s) <= 40 else s[:37] + "..."


def check_same(runs: Sequence[SeedRun], mix: bool = False) -> list[str]:
    """Refuse (ConfigError, one line naming the first differing key) when the training seeds were run with different
    settings; with ``mix`` return those differences instead (one line each) so the report can say what it mixed."""
    notes: list[str] = []
    if len(runs) < 2:
        return notes
    seeds = [r.seed for r in runs]
    if len(set(seeds)) != len(seeds):
        dup = sorted({s for s in seeds if seeds.count(s) > 1})
        where = ", ".join(r.source for r in runs if r.seed == dup[0])
        raise ConfigError(f"training seed {dup[0]} appears twice ({where})")

    def compare(what: str, dicts: list[tuple[int, dict]]) -> None:
        keys = sorted({k for _, d in dicts for k in d}, key=lambda k: (k != "picked by select", k))
        for k in keys:
            vals = [(s, d.get(k, "<absent>")) for s, d in dicts]
            if len({json.dumps(v, sort_keys=True, default=str) for _, v in vals}) > 1:
                (s0, v0), (s1, v1) = vals[0], next((s, v) for s, v in vals if v != vals[0][1])
                line = (f"{what}{k} differs across training seeds (seed {s0}: {_show(v0)}, seed {s1}: {_show(v1)})")
                if not mix:
                    raise ConfigError(f"{line}; report them apart, or mix them with report.mix=true")
                notes.append(line)

    compare("", [(r.seed, r.settings) for r in runs])
    for key in sorted({k for r in runs for k in r.entries}):
        have = [(r.seed, r.entries[key].settings) for r in runs if key in r.entries]
        compare(f"{key}: ", have)
    return notes


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
    from .schemes import SCHEMES as BASELINES

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
        for m in [m for m in METRICS if all(m in r.entries[key].rows[0] for r in have)]:
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

    f = Path(__file__).resolve().parent.parent / "conf" / "budget" / f"{budget}.yaml"
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
                vals = {m: [row[m] for row in e.rows] for m in METRICS if m in e.rows[0]}
                algos.setdefault(key, {})[f"seed{r.seed}"] = {"step_1": {"step_count": steps, **vals},
                                                              "absolute_metrics": vals}
        out[environment][task] = algos
    return out


# ------------------------------------------------------------------------------------------------ figures
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

    from .plotting import profile_plot, seeds_plane

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
        made.append(seeds_plane(pts, across, f"{task} ({budget} budget): loss against max degree over training "
                                f"seeds\n{what}; lower left is better", out_dir / f"seeds-{task}.png"))
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
                                 note, out_dir / "seeds-profile.png"))
    return made
