"""The sections over training seeds (docs/results/seeds/*.json): per task the across-seed table, the probability of
improvement and the claims per seed and across seeds; the claims at a glance over seeds."""

from __future__ import annotations

from neurosym_cli.stats import mean_ci

from .claims import Claim, claims
from .files import FIGURES, FORMATION, PLANNED_SEEDS, SEED_TASKS, seed_variant


def seed_claims(task: str, runs: list) -> tuple[list[str], dict[int, list[Claim] | str]]:
    """Per training seed its claims (or why none: a baseline missing); and the claim names in order."""
    per: dict[int, list[Claim] | str] = {}
    names: list[str] = []
    for r in runs:
        try:
            per[r.seed] = claims(task, seed_variant(r))
            names = names or [c.name for c in per[r.seed]]
        except KeyError as e:
            per[r.seed] = f"not checked: {e.args[0]} not evaluated"
    return names, per


def claim_over_seeds(name: str, per: dict, digits: int) -> dict:
    """A claim across seeds: how many seeds it holds on, of how many checked, and its quantity's mean with the
    95 % t half-width across seeds (None for one seed)."""
    cs = [next(c for c in cl if c.name == name) for cl in per.values() if not isinstance(cl, str)]
    k, n = sum(c.holds for c in cs), len(cs)
    m, h = mean_ci([c.value for c in cs]) if cs else (None, None)
    unit = cs[0].unit if cs else ""
    pct = " %" if cs and cs[0].quantity == "gap" else ""
    sign = "" if cs and cs[0].quantity == "mean" else "+"  # a loss itself, not a difference: unsigned
    if not cs:
        across = "-"
    elif n == 1:
        across = f"{m:{sign}.{digits}f}{pct} (one seed: no interval)"
    else:
        across = f"{m:{sign}.{digits}f} ± {h:.{digits}f}{pct}"
    return {"k": k, "n": n, "across": across.replace("-", "−") if cs else across, "unit": unit, "short": name}


def holds_cell(c: dict) -> str:
    """'holds on k/n' (bold when on every seed: the claim holds)."""
    if c["n"] == 0:
        return "not checked"
    text = f"holds on {c['k']}/{c['n']}"
    return f"**{text}**" if c["k"] == c["n"] else text


def _seed_table(task: str, runs: list) -> list[str]:
    from neurosym_cli import seeds

    s = seeds.summarize(runs)
    n = len(s.seeds)
    digits = 3 if task == "unlabeled-goals" else 2
    ev = next(iter(runs[0].entries.values())).rows
    if n == 1:
        head = (f"One training seed: its model's mean over the {len(ev)} evaluation seeds ± the 95 % Student-t "
                "interval over those evaluation seeds (episode noise of one trained model); no interval across one "
                "training seed, no IQM.")
    else:
        head = (f"Each training seed contributes one number per baseline, its model's mean over the {len(ev)} "
                f"evaluation seeds. Loss and degrees: mean ± 95 % Student-t interval across the {n} training seeds "
                f"({n - 1} degree{'s' if n > 2 else ''} of freedom); loss IQM [95 % stratified bootstrap percentile "
                "interval] (rliable; with fewer than 4 seeds the IQM is the mean).")

    def cell(m: dict) -> str:
        if m["n"] == 1 and n == 1:
            return f"{m['mean']:.{digits}f} ± {m['eval_ci95']:.{digits}f}"
        return seeds.fmt_mean(m, digits)

    out = [head, "", "| baseline | n seeds | loss | loss IQM [95 % bootstrap] | max in | max out | "
           "max in+out |", "|---|---|---|---|---|---|---|"]
    for key, m in s.rows.items():
        out.append(f"| {key} | {m['cost']['n']} | {cell(m['cost'])} | {seeds.fmt_iqm(m['cost'], digits)} | "
                   f"{cell(m['max_in'])} | {cell(m['max_out'])} | {cell(m['max_degree'])} |")
    if s.improvement and n > 1:
        out += ["", "Probability that prog-retrained improves on each baseline's loss across training seeds (the "
                "share of seed pairs where its loss is lower, ties counting 1/2; [95 % stratified bootstrap "
                "percentile interval]; 0.5 = no difference):", "",
                "| prog-retrained vs | P(improves) | seeds |", "|---|---|---|"]
        out += [f"| {r['y']} | {seeds.fmt_p(r)} | {r['n_x']} / {r['n_y']} |" for r in s.improvement]
    return out


def seeds_task(task: str, runs: list) -> str:
    """One task over training seeds: the seeds run and their picks, the across-seed table, the probability of
    improvement, the claims per seed and across seeds, the loss-degree figure when drawn."""
    out = [f"### {task} over training seeds", ""]
    if not runs:
        return "\n".join(out + [f"Not yet run: no seed file `docs/results/seeds/{task}-seed<S>.json` (training seeds "
                                 f"{', '.join(map(str, PLANNED_SEEDS))} are planned; benchmarks/run_seeds.py)."])
    have = [r.seed for r in runs]
    missing = [s for s in PLANNED_SEEDS if s not in have]
    budget = runs[0].settings.get("budget")
    picks = "; ".join(f"seed {r.seed} K = {r.pick['rules']}, λ {r.pick['lam']:g}, {r.pick['features']}"
                      for r in runs if r.pick)
    out += [f"Training seed{'s' if len(have) > 1 else ''} {', '.join(map(str, have))} ({len(have)} of "
            f"{len(PLANNED_SEEDS)}" + (f"; seed{'s' if len(missing) > 1 else ''} {', '.join(map(str, missing))} not "
                                      "yet run" if missing else "") + f"), {budget} budget: on each "
            "seed `neurosym select` picked K, λ and the features by validation, then `neurosym pipeline "
            f"selected=true` made and evaluated every baseline (pinned CPU kernels). Picks: {picks}.", ""]
    out += _seed_table(task, runs)
    names, per = seed_claims(task, runs)
    digits = 3 if task == "unlabeled-goals" else 2
    out += ["", "Claims of the paper per training seed (yes/no on that seed's evaluation seeds, as in the sections "
            "above) and across seeds: \"holds on k/n\" (bold when on every seed: the claim holds), and the quantity "
            "the verdict reads, mean ± 95 % Student-t interval across training seeds:", "",
            "| claim | " + " | ".join(f"seed {s}" for s in have) + " | holds on | across seeds | quantity |",
            "|---" * (len(have) + 4) + "|"]
    for name in names:
        c = claim_over_seeds(name, per, digits)
        cells = []
        for s in have:
            cl = per[s]
            if isinstance(cl, str):
                cells.append(cl)
                continue
            one = next(x for x in cl if x.name == name)
            cells.append(("yes, " if one.holds else "**no**: ") + one.cell)
        out.append(f"| {c['short']} | " + " | ".join(cells) + f" | {holds_cell(c)} | {c['across']} | {c['unit']} |")
    if (FIGURES / f"seeds-{task}.png").exists():
        out += ["", f"![{task}: loss against max in+out over training seeds, one marker per seed and the across-seed "
                f"mean ± 95 % t-interval](figures/seeds-{task}.png)"]
    return "\n".join(out)


def seeds_section(by_task: dict) -> str:
    """{{seeds}}: every task of SEED_TASKS over its training seeds, then the performance profile when drawn."""
    parts = [seeds_task(t, by_task.get(t, [])) for t in SEED_TASKS]
    if (FIGURES / "seeds-profile.png").exists():
        parts.append("![performance profile of normalized loss over tasks and training seeds: 1 = the seed's "
                     "tf-full, 0 = its no-comm](figures/seeds-profile.png)")
    return "\n\n".join(parts)


def seeds_glance(by_task: dict) -> str:
    """{{seeds_glance}}: per task family a row per claim, a column per task, each cell "holds on k/n" with the
    across-seed interval of the claim's quantity ("not yet run" where a task has no seed file)."""
    out = []
    for family, tasks in (("paper section 4", [t for t in SEED_TASKS if t in FORMATION]),
                          ("unlabeled-goals", [t for t in SEED_TASKS if t not in FORMATION])):
        digits = 3 if family == "unlabeled-goals" else 2
        per_task = {t: seed_claims(t, by_task.get(t, [])) for t in tasks}
        names = next((n for n, _ in per_task.values() if n), [])
        out += [f"| claim ({family}) | " + " | ".join(
            f"{t} ({len(by_task.get(t, []))} seed{'' if len(by_task.get(t, [])) == 1 else 's'})" for t in tasks)
            + " |", "|---" * (len(tasks) + 1) + "|"]
        if not names:
            out += ["| every claim | " + " | ".join("not yet run" for _ in tasks) + " |", ""]
            continue
        for name in names:
            cells, label = [], None
            for t in tasks:
                n_t, per = per_task[t]
                if not by_task.get(t):
                    cells.append("not yet run")
                    continue
                c = claim_over_seeds(name, per, digits)
                label = label or c["short"]
                cells.append(f"{holds_cell(c)}; {c['across']}")
            out.append(f"| {label or name} | " + " | ".join(cells) + " |")
        out.append("")
    return "\n".join(out)


def seed_mean(by_task: dict, task: str, seed: int, baseline: str, metric: str = "cost") -> float:
    """One training seed's mean of ``metric`` for ``baseline`` over its evaluation seeds (KeyError if absent)."""
    run = next((r for r in by_task.get(task, []) if r.seed == seed), None)
    if run is None:
        raise KeyError(f"{task} training seed {seed} (no seed file)")
    return seed_variant(run)["baselines"][baseline]["summary"][metric]["mean"]
