"""Where the page's inputs live, the protocol's variants and names, and reading the small result files."""

from __future__ import annotations

import json
from pathlib import Path

from benchmarks.run_seeds import KEEP_SELECT, SEEDS as PLANNED_SEEDS, TASKS as SEED_TASKS  # noqa: F401  (one place)
from benchmarks.run_seeds import write_result as write  # noqa: F401  (a result file, atomically)
from neurosym_cli.schemes import SCHEMES, default_baselines
from neurosym_cli.seeds.read import METRICS  # noqa: F401  (the metrics a result file keeps per baseline)

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
RESULTS = DOCS / "results"
FIGURES = DOCS / "figures"
"""the page's figures (docs/figures/)"""
TEMPLATE = DOCS / "results.template.md"
SEEDS = RESULTS / "seeds"
ORDER = default_baselines()
"""the baselines of the paper's protocol in the order of every table (neurosym_cli/schemes)"""

# variant -> (task, lambda of its programs or None for the task's, objective); the protocol's one command per
# task, and the two follow-up searches (run_paper.py --followups)
VARIANTS = {
    "random-cross": ("random-cross", None, "paper"),
    "random-grid": ("random-grid", None, "paper"),
    "random-grid-lam0.2": ("random-grid", 0.2, "paper"),
    "unlabeled-goals": ("unlabeled-goals", None, "paper"),
    "unlabeled-goals-hinge": ("unlabeled-goals", None, "hinge"),
}
FORMATION = ("random-cross", "random-grid")
"""the formation-flying tasks of paper section 4 (their claims differ from unlabeled-goals')"""
TRAINING = ("rollouts", "seconds_this_run", "rollouts_per_second", "final_loss")
"""what a result file keeps of a training manifest"""


def has_program(metrics: dict) -> bool:
    """An evaluation of a baseline that runs under a program (prog, det-prog and their retrainings)."""
    return getattr(SCHEMES.get(metrics["baseline"]), "has_program", False)


def entry(m: dict, *, metrics=METRICS, stats=("mean", "std"), optional=False, **extra) -> dict:
    """An evaluation's metrics.json -> a baseline's entry in a result file: its label, the summary (``stats`` of
    each of ``metrics`` over the evaluation seeds; with ``optional``, those the evaluation has) and the loss of
    every evaluation seed; ``extra``: more keys."""
    keys = [k for k in metrics if k in m["summary"]] if optional else metrics
    return {"label": m["label"], **extra,
            "summary": {k: {x: m["summary"][k][x] for x in stats} for k in keys},
            "cost_per_seed": {str(r["seed"]): r["cost"] for r in m["per_seed"]}}


def read(name: str) -> dict:
    """docs/results/<name>.json."""
    return json.loads((RESULTS / f"{name}.json").read_text())


def load() -> tuple[dict[str, dict], dict]:
    """The variants' result files that exist (by variant name) and run.json ({} when absent)."""
    variants = {n: read(n) for n in VARIANTS if (RESULTS / f"{n}.json").exists()}
    run = read("run") if (RESULTS / "run.json").exists() else {}
    return variants, run


def load_seeds(directory: Path = SEEDS) -> dict:
    """The seed files of ``directory`` grouped by task (neurosym_cli.seeds.SeedRun, seed order); {} when none."""
    from neurosym_cli import seeds

    return seeds.from_seed_files(sorted(Path(directory).glob("*.json"))) if Path(directory).is_dir() else {}


def seed_variant(r) -> dict:
    """One training seed in the variant format that ``claims`` reads (summaries recomputed from the per-seed
    rows)."""
    base = {}
    for b, e in r.entries.items():
        summary = {}
        for k in METRICS:
            xs = [row[k] for row in e.rows]
            m = sum(xs) / len(xs)
            sd = (sum((x - m) ** 2 for x in xs) / (len(xs) - 1)) ** 0.5 if len(xs) > 1 else 0.0
            summary[k] = {"mean": m, "std": sd}
        base[b] = {"label": e.label, "summary": summary,
                   "cost_per_seed": {str(row["seed"]): row["cost"] for row in e.rows}}
    return {"task": r.task, "baselines": base, "seeds": len(next(iter(r.entries.values())).rows),
            **(r.pick or {})}


def with_selected(v: dict, sel: dict) -> dict:
    """Variant ``v`` with its prog and prog-retrained replaced by the selected program's test evaluations."""
    return {**v, "baselines": {**v["baselines"], **sel["test"]}, "rules": sel["rules"], "lam": sel["lam"],
            "features": sel["features"]}
