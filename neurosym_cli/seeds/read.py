"""The evaluations of one task over its training seeds, read from run directories or committed seed files, and the
check that the seeds were run alike (see the package docstring)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Sequence

from .. import stats
from ..degrees import METRICS as SHARED  # the metrics every evaluation has
from ..errors import ConfigError
from ..run.layout import RunFolder, is_front_pick
from ..utils.io import ArtifactError

METRICS = SHARED + ("collisions",)
"""what the tables report first: the shared metrics, then the paper tasks' own (a task without it reports without
it); any other metric an evaluation holds follows (metric_order)"""

NOT_METRICS = ("seed", "episodes")
"""the keys of a per-evaluation-seed row that say which seed it is, not how it went"""


def metric_order(keys: Iterable[str]) -> list[str]:
    """The metric keys among ``keys`` in the order every table shows them: METRICS first, then any other a task
    (``Task.metrics``) or a scheme records, in the order first met."""
    found = list(dict.fromkeys(k for k in keys if k not in NOT_METRICS))
    return [m for m in METRICS if m in found] + [k for k in found if k not in METRICS]

METHOD = "prog-retrained"
"""the baseline whose probability of improvement over every other one is reported"""

PAIRS = ("tf-full", "dist", "no-comm", "expo")
"""the comparisons of METHOD named first (the others present follow)"""

IGNORED = ("cmd", "seed", "exp_dir", "runs_root", "report_dir", "report", "device", "threads", "progress", "plots",
           "logger", "overwrite", "baselines", "episode", "render", "stress", "select.jobs", "rl.jobs", "selected",
           "baseline", "program_file", "tune")
"""config keys (and prefixes) that do not change a result, or that name the baseline rather than the run (tune: the
settings of `neurosym tune`, which evaluates nothing on the test seeds; records before it lack them)"""

PICKED = ("rules", "lam", "features", "synth")
"""what `neurosym select` chooses per training seed (K, lambda, features, search settings): allowed to differ"""

ADDED = ("synth.front_budgets", "synth.front_steps")
"""config keys added to the schema on 2026-12-03: a record written before lacks them, and its run is what their
schema default does, so it reads as that default"""

BEFORE = {"task.objective": "paper", "compile": "off", "synth.search": "mcmc", "synth.front": False,
          "pipeline.select": "none", "pipeline.margin": None}
"""config keys added with another default than what the code did before them: what a record without them ran
(every task's objective was the paper's before task.objective, a task that states none now composes scaled; the
step was eager before compile=; the search was MCMC without a front and the pipeline ran its single-lam program
before issue 37 made hybrid, the front and the pick among it the defaults)"""


def schema_default(key: str) -> Any:
    """The default of a dotted config key in RunConfig's schema ("synth.search" -> "mcmc")."""
    import dataclasses

    from ..config import RunConfig

    obj: Any = RunConfig
    for part in key.split("."):
        f = next(f for f in dataclasses.fields(obj) if f.name == part)
        obj = f.default_factory() if f.default is dataclasses.MISSING else f.default  # type: ignore[misc]
    return obj


def as_run(key: str, settings: dict[str, Any]) -> Any:
    """A record's setting ``key`` (of its flattened ``settings``) as what its run did, so that seeds of older and
    newer code that made the same run compare equal: a key the record predates reads as what the code did then
    (``ADDED``, ``BEFORE``; other absent keys '<absent>'); compile as the step in effect (auto: eager, as off); an
    empty select.lam as the grid it stands for (degrees.LAM_GRIDS of the record's objective)."""
    if key not in settings:
        return schema_default(key) if key in ADDED else BEFORE.get(key, "<absent>")
    value = settings[key]
    if key == "compile" and isinstance(value, str):
        from ..utils.compiling import resolve

        return "on" if resolve(value) else "off"
    if key == "select.lam" and value == []:
        from ..degrees import LAM_GRIDS

        return LAM_GRIDS.get(settings.get("synth.objective", "paper"), value)
    return value


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


def non_finite(rows: Iterable[Any], metrics: Sequence[str] | None = None) -> str | None:
    """Where the first nan or inf among the ``metrics`` (default: every metric of the row) of per-evaluation-seed
    rows is ("cost of evaluation seed 3 is nan"), or None. JSON readers accept NaN and Infinity, and one of them turns every mean, interval, IQM and
    Pareto front it enters into nan or inf that print as results."""
    for i, r in enumerate(rows):
        if not isinstance(r, dict):
            continue
        for m in metric_order(r) if metrics is None else metrics:
            v = r.get(m)
            if isinstance(v, (int, float)) and not isinstance(v, bool) and not math.isfinite(v):
                return f"{m} of evaluation seed {r.get('seed', i)} is {v}"
    return None


NOT_A_RESULT = "not a result, and no table, interval or Pareto front is computed over it"
"""why a nan or inf in an evaluation is refused, said in every such error"""


def refuse_non_finite(rows: Iterable[Any], where: str, again: str) -> None:
    """One ArtifactError naming ``where`` and the key when a row holds a nan or inf; ``again``: what to do."""
    bad = non_finite(rows)
    if bad:
        raise ArtifactError(f"{where}: {bad}, {NOT_A_RESULT}; {again}")


def _rows(per_seed: Any, where: str, again: str = "evaluate it again") -> list[dict[str, float]]:
    if not (isinstance(per_seed, list) and per_seed
            and all(isinstance(r, dict) and all(isinstance(r.get(m), (int, float)) for m in SHARED)
                    for r in per_seed)):
        raise ArtifactError(f"{where} has no per-evaluation-seed rows with {', '.join(SHARED)}; evaluate it again")
    refuse_non_finite(per_seed, where, again)
    return [{m: float(r[m]) for m in metric_order(r) if isinstance(r[m], (int, float)) and not isinstance(r[m], bool)}
            | {"seed": r.get("seed")} for r in per_seed]


def _remake(seed_dir: Path, verb: str, files: list[Path]) -> str:
    """The command that writes a seed directory's files again (`neurosym <verb> task=... budget=... seed=...
    runs_root=...`), its settings read from a train manifest or evaluation of that directory that still reads;
    the bare verb when none does."""
    import shlex

    for f in [*RunFolder(seed_dir).manifests(), *files]:
        try:
            c = json.loads(f.read_text())
            c = c.get("config", c) if isinstance(c, dict) else {}
            args = [f"task={c['task']['name']}", f"budget={c['budget']['name']}", f"seed={int(c['seed'])}",
                    f"runs_root={c['runs_root']}"]
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            continue
        return f"`neurosym {verb} {shlex.join(args)}`"
    return f"`neurosym {verb}` for that task, budget and seed"


def from_run_dir(seed_dir: Path, task: str = "") -> SeedRun | None:
    """The evaluations of one seed directory (None when it has none)."""
    files = RunFolder(seed_dir).metrics_files()
    if not files:
        return None
    pick = None
    sel = RunFolder(seed_dir).selected_file
    if sel.exists():
        try:
            rec = json.loads(sel.read_text())
            pick = {k: rec[k] for k in ("rules", "lam", "features")}
        except (OSError, ValueError, KeyError, TypeError):
            raise ArtifactError(f"{sel} is not a selection written by `neurosym select`; delete it and run "
                                f"{_remake(seed_dir, 'select', files)}") from None
    raw = []
    for f in files:
        try:
            m = json.loads(f.read_text())
            raw.append((f, m["baseline"], m["label"], m.get("config") or {}, m["per_seed"]))
        except (OSError, ValueError, KeyError, TypeError):
            raise ArtifactError(f"{f} is not an evaluation written by `neurosym eval`; delete it and run "
                                f"{_remake(seed_dir, 'pipeline', files)}") from None
    by_baseline: dict[str, list[tuple[str, dict]]] = {}
    for _, b, label, c, _ in raw:
        by_baseline.setdefault(b, []).append((label, c))
    entries: dict[str, Entry] = {}
    settings: dict[str, Any] = {}
    seed = None
    for f, b, label, c, per_seed in raw:
        key = _key_of(b, by_baseline[b], pick, label, c)
        picked = bool(c.get("selected")) or (pick is not None and all(c.get(k) == pick[k] for k in pick))
        front = is_front_pick(c.get("program") or "")  # pipeline.select=front's pick: the method's outcome per seed
        flat = {"picked by select": picked, **{k: v for k, v in flatten(c).items()
                                               if not _ignored(k, picked) and not (front and k == "program")}}
        entries[key] = Entry(label, _rows(per_seed, str(f), f"delete it and run {_remake(seed_dir, 'eval', files)} "
                                          "for that baseline, or leave this seed out of report_dir"), flat)
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
        entries = {b: Entry(e["label"], _rows(e["per_seed"], f"{path} (baseline {b})", "run that seed again "
                                              "(benchmarks/run_seeds.py), or move the file out of report.seed_files"),
                            {})
                   for b, e in r["baselines"].items()}
        sel = r.get("selected") or {}
        grid = sorted({(p.get("lam"), p.get("rules"), p.get("features")) for p in r.get("selection") or []},
                      key=str)
        machine = r.get("machine") or {}
        kernels = machine.get("cpu_kernels")
        if kernels == "avx2" and not machine.get("mkl_path"):
            kernels = "avx2-vendor"  # written before 2026-12-03, when avx2 left MKL its own path per CPU vendor
        settings = {"budget": r["budget"], "cpu_kernels": kernels,
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
            vals = [(s, as_run(k, d)) for s, d in dicts]
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


