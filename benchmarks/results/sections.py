"""The sections of one training seed: a variant's table, programs, stage times and claims; the claims at a glance;
`neurosym select`'s ranking and pick; `neurosym stress`'s tables."""

from __future__ import annotations

from .claims import claims
from .files import FIGURES, FORMATION, ORDER, VARIANTS, read, with_selected
from .tables import EVAL_PM, ms, readings, shown, verdict


def title(name: str, v: dict) -> str:
    """A variant's heading: the task, and the programs' lambda and objective where they are not the task's."""
    _, lam, objective = VARIANTS[name]
    if lam is None and objective == "paper":
        return v["task"]
    return f"{v['task']} (programs: lambda {v['lam']:g}, {objective} objective)"


def section(name: str, v: dict) -> str:
    """{{section V}}: variant V's table, figure, programs with their readings, stage times and claim lines."""
    task = v["task"]
    out = [f"## {title(name, v)}", "", f"K = {v['rules']}, lambda = {v['lam']:g}, objective {v['objective']}, "
           f"{v['seeds']} evaluation seeds; loss and degrees: {EVAL_PM}.", "",
           "| baseline | loss | max in | max out | mean in+out |", "|---|---|---|---|---|"]
    digits = 3 if task == "unlabeled-goals" else 2
    for b in sorted(v["baselines"], key=lambda b: ORDER.index(b) if b in ORDER else len(ORDER)):
        out.append(f"| {b} | {ms(v, b, 'cost', digits)} | {ms(v, b, 'max_in')} | {ms(v, b, 'max_out')} | "
                   f"{ms(v, b, 'mean_degree')} |")
    if name == task and (FIGURES / f"{task}.png").exists():
        out += ["", f"![{task}: loss vs max in-degree](figures/{task}.png)"]
    out += ["", "Synthesized programs, each rule with its reading (`neurosym show-program` prints the same):", ""]
    for tag, raw in sorted(v["programs"].items()):
        text, program, said = shown(raw, v["task"], v["features"], v["objective"])
        out += [f"`{tag}`:", "", "```", text, "```", "", *([*said, ""] if said else [])]
        out += readings(program, v["task"], v["features"])
        out.append("")
    if "timings" in v:
        t = v["timings"]
        total = sum(t.values())
        out += ["Wall time per stage (one CPU thread each, two stages at a time on the 2 cores):", "",
                "| stage | seconds |", "|---|---|"] + [f"| {k} | {s:.0f} |" for k, s in t.items()]
        out += [f"| **total** | **{total:.0f}** ({total / 60:.1f} min) |", ""]
    out += ["Claims of the paper:", ""] + [f"- {c.long} -> {verdict(c.holds)}" for c in claims(task, v)]
    return "\n".join(out) + "\n"


def glance(variants: dict[str, dict]) -> str:
    """One table per task family: a row per claim, a column per variant; each cell says yes or no and why."""
    out = []
    for fam, names in (("paper section 4", [n for n in variants if variants[n]["task"] in FORMATION]),
                       ("unlabeled-goals", [n for n in variants if variants[n]["task"] == "unlabeled-goals"])):
        if not names:
            continue
        cols = [f"{variants[n]['task']} (λ {variants[n]['lam']:g}"
                + (", hinge objective)" if variants[n]["objective"] == "hinge" else ")") for n in names]
        rows = [claims(variants[n]["task"], variants[n]) for n in names]
        out += [f"| claim ({fam}) | " + " | ".join(cols) + " |", "|---" * (len(cols) + 1) + "|"]
        for k, first in enumerate(rows[0]):
            cells = [("yes, " if r[k].holds else "**no**: ") + r[k].cell for r in rows]
            out.append(f"| {first.short} | " + " | ".join(cells) + " |")
        out.append("")
    return "\n".join(out)


def selection(task: str, variants: dict[str, dict]) -> str:
    """{{selection T}}: ranked table, pick, test numbers, claims with the pick, Pareto figure (select-T.json)."""
    from neurosym_cli.stages.select import choose

    sel = read(f"select-{task}")
    v = variants[task]
    first = choose(sel["programs"])
    final = {r["name"]: r for r in choose(sel["retrained"])}
    # wall times: as the command measured them, or, where it ran in two invocations, from their logs ("wall")
    sec = sel.get("wall") or {"search_and_validate": sel["seconds"]["search_and_validate"],
                              "finalists_and_test": sel["seconds"]["total"] - sel["seconds"]["search_and_validate"]}
    total = sec["search_and_validate"] + sec["finalists_and_test"]
    out = [f"Grid: lambda {sel['grid']['lam']}, K {sel['grid']['rules']}, features {sel['grid']['features']} "
           f"({len(sel['programs'])} programs) on the oracle and dataset D of the {task} section, searched with "
           f"`synth.coarse={sel['synth']['coarse']} synth.patience={sel['synth']['patience']}`; "
           f"{sel['val_seeds']} validation seeds; up to {sel['finalists']} finalists retrained. "
           f"Wall time on 2 cores ({sel['jobs']} one-thread jobs): **{total / 60:.1f} min** in all: "
           f"{sec['search_and_validate'] / 60:.1f} min searching and validating the {len(sel['programs'])} programs, "
           f"{sec['finalists_and_test'] / 60:.1f} min retraining and validating the finalists and evaluating the "
           f"pick on the test seeds." + (f" {sec['note']}" if sec.get("note") else ""), "",
           "| # | lam | K | feat | search objective | val loss (prog) | Δ to best ± 95 % | max in+out | retrained val loss"
           " | retrained max in+out | |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for rank, r in enumerate(sorted(first, key=lambda r: r["loss_mean"]), start=1):
        f = final.get(r["name"])
        mark = "**picked**" if f and f["picked"] else ("finalist" if f else "")
        ret = "" if f is None else f"{f['loss_mean']:.2f} ± {f['loss_ci']:.2f}" + ("" if f["similar"] else " (worse)")
        out.append(f"| {rank} | {r['lam']:g} | {r['rules']} | {r['features']} | {r['objective']:.3f} | "
                   f"{r['loss_mean']:.2f} ± {r['loss_ci']:.2f} | {r['diff']:+.2f} ± {r['diff_ci']:.2f}"
                   + ("" if r["similar"] else " *") + f" | {r['degree']:.2f} | {ret} | "
                   + ("" if f is None else f"{f['degree']:.2f}") + f" | {mark} |")
    out += ["", "\\* worse than the validation-best: the paired 95 % interval of the difference excludes 0.", ""]
    out += [f"The pick: **K = {sel['rules']}, lambda = {sel['lam']:g}, features {sel['features']}** "
            f"(task default: K = {v['rules']}, lambda = {v['lam']:g}, {v['features']}):", ""]
    text, program, said = shown(sel["program"], sel["task"], sel["features"])
    out += ["```", text, "```", "", *([*said, ""] if said else [])]
    out += readings(program, sel["task"], sel["features"])
    out.append("")
    vs = with_selected(v, sel)
    out += [f"Test seeds ({v['seeds']}, the same episodes as the table above), the pick against the default "
            f"configuration's programs ({EVAL_PM}):", "",
            "| baseline | loss | max in | max out | mean in+out |", "|---|---|---|---|---|"]
    for b in ("tf-full", "hard-attn", "dist", "prog", "prog-retrained", "no-comm"):
        if b in ("prog", "prog-retrained"):
            out.append(f"| {b} (default {v['baselines'][b]['label'].split(b + '-')[-1]}) | {ms(v, b, 'cost')} | "
                       f"{ms(v, b, 'max_in')} | {ms(v, b, 'max_out')} | {ms(v, b, 'mean_degree')} |")
            out.append(f"| **{b} (selected {sel['name']})** | {ms(vs, b, 'cost')} | {ms(vs, b, 'max_in')} | "
                       f"{ms(vs, b, 'max_out')} | {ms(vs, b, 'mean_degree')} |")
        elif b in v["baselines"]:
            out.append(f"| {b} | {ms(v, b, 'cost')} | {ms(v, b, 'max_in')} | {ms(v, b, 'max_out')} | "
                       f"{ms(v, b, 'mean_degree')} |")
    out += ["", "The paper's claims with the selected program (prog, prog-retrained replaced by the pick):", ""]
    before = {c.short: c.holds for c in claims(task, v)}
    for c in claims(task, vs):
        if "det-prog" in c.short:  # its programs were searched with the default lambda and features, not the pick's
            out.append(f"- {c.short}: not re-checked (det-prog was not searched with the picked lambda and features)")
            continue
        change = "" if before.get(c.short) == c.holds else f" (with the default configuration: {verdict(before[c.short])})"
        out.append(f"- {c.long} -> {verdict(c.holds)}{change}")
    if (FIGURES / f"{task}-pareto-selected.png").exists():
        out += ["", f"![{task}: loss against max in+out, Pareto front](figures/{task}-pareto-selected.png)"]
    return "\n".join(out)


def stress(task: str) -> str:
    """{{stress T}}: one table per axis (loss / max in / max out per baseline), the figure (stress-T.json)."""
    st = read(f"stress-{task}")
    out = []
    for axis, head in (("agents", "agents per group (no link failure)"),
                       ("failure", f"link failure rate ({st['trained_agents_per_group']} agents per group)")):
        rows = [r for r in st["results"] if r["axis"] == axis]
        if not rows:
            continue
        key = "agents_per_group" if axis == "agents" else "link_failure"
        levels = sorted({r[key] for r in rows})
        names = {r[key]: (f"{r[key]} (N ≤ {r['max_agents']})" if axis == "agents" else f"{r[key]:g}") for r in rows}
        out += [f"Loss / max in / max out by {head}, mean over {st['seeds']} test seeds:", "",
                "| baseline | " + " | ".join(names[k] for k in levels) + " |", "|---" * (len(levels) + 1) + "|"]
        for label in dict.fromkeys(r["label"] for r in rows):
            cells = []
            for k in levels:
                r = next((r for r in rows if r["label"] == label and r[key] == k), None)
                cells.append("-" if r is None else f"{r['cost']['mean']:.1f} / {r['max_in']['mean']:.2f} / "
                                                   f"{r['max_out']['mean']:.2f}")
            out.append(f"| {label} | " + " | ".join(cells) + " |")
        out.append("")
    if st.get("skipped"):
        out += ["Not stressed (not trained in that run directory): " + ", ".join(sorted(st["skipped"])) + ".", ""]
    if (FIGURES / f"{task}-stress.png").exists():
        out.append(f"![{task}: zero-shot stress](figures/{task}-stress.png)")
    return "\n".join(out).rstrip("\n")
