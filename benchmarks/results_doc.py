"""docs/results.md from one template (docs/results.template.md) and the small result files beside it (docs/results/).

    python benchmarks/results_doc.py --collect   # outputs/ (the paper protocol's artifacts) -> docs/results/*.json
    python benchmarks/results_doc.py             # docs/results/*.json + the template -> docs/results.md
    python benchmarks/results_doc.py --check     # exit 1 when docs/results.md is not what the files give
    python benchmarks/results_doc.py --figures   # also redraw the Figure-2 pictures from the result files
    python benchmarks/results_doc.py --seeds DIR --out /tmp/page.md --seed-figures /tmp/figs   # preview other seeds

Every number of the document comes from the result files: one per variant of the protocol (a task, with the
lambda and objective of its programs), holding each baseline's summary (mean and std over the evaluation seeds),
its per-seed losses (for paired intervals), the synthesized programs and the stage times; and run.json (wall
times of the whole protocol). The template's placeholders, ``{{op args}}``, are looked up in a table of
functions below (never evaluated as code):

    {{section V}}            the table, figure, programs, stage times and claim lines of variant V
    {{glance}}               the claims-at-a-glance tables of every variant
    {{mean V B M D}}         baseline B's mean of metric M in variant V, D digits (M: cost, max_in, max_out, ...)
    {{half V B M D}}         half of it (mean in+out / 2 = edges heard per agent and step)
    {{per V B M1 M2 D}}      mean of M1 / mean of M2
    {{paired V A B D}}       paired loss difference A - B over the evaluation seeds with its 95 % t half-width
    {{gap V A B}}            relative loss difference A vs B, in percent
    {{run KEY D}}            a figure of run.json (minutes)
    {{stress T}}             `neurosym stress` on task T: loss and degrees at other team sizes and under link failure
    {{rl T}}                 `neurosym rl` on task T (appendix D): the grid, rl1 and rl2 beside the others, the claims
    {{noisy T C}}            appendix E: link-failure task T (T.json, select-T.json) against its clean task C
    {{selection T}}          `neurosym select` on task T: the ranked table, the pick, its test numbers, the
                             paper's claims re-checked with it, the loss-degree Pareto front (select-T.json)
    {{seeds}}                every task over its training seeds (docs/results/seeds/*.json): mean ± t-interval
                             and IQM [bootstrap] per baseline, probability of improvement, claims per seed and
                             across seeds ("holds on k/n"), the loss-degree figure; "not yet run" without files
    {{seeds_glance}}         the claims at a glance over training seeds: cells "holds on k/n; mean ± t-interval"
    {{seeds_planned}}        the training seeds the protocol runs (0, 1, 2)

Loss claims use paired differences over the evaluation seeds (every baseline sees the same episodes for a seed)
with a 95 % t-interval.
"""

from __future__ import annotations

import argparse
import csv
import functools
import json
import re
import sys
from pathlib import Path
from typing import NamedTuple

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from neurosym_cli.dsl import describe, parse  # noqa: E402  (the readings come from the project's own printer)
from neurosym_cli.schemes import SCHEMES  # noqa: E402
from neurosym_cli.stats import mean_ci, t95  # noqa: E402  (one Student-t interval for the page and `select`)


@functools.lru_cache(maxsize=None)
def vocab(task: str, features: str):
    """The declared features of a task (their words make the readings), from its config as `neurosym` composes it."""
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.tasks import make_task

    cfg = compose_config("show_program", [f"task={task}", f"features={features}"])
    return make_task(cfg.task).features(features).vocab


def shown(text: str, task: str, features: str, objective: str = "paper"):
    """A committed program as the page shows it: simplified by the rewrites that hold whatever the data
    (neurosym_cli/synth/simplify.py ``simplify_static``; the result file keeps the program as it was evaluated),
    its header's degree term in the page's words. Returns (text, Program, the lines the page says under it)."""
    from neurosym_cli.degrees import objective_term
    from neurosym_cli.dsl import to_text
    from neurosym_cli.dsl.ast import Program
    from neurosym_cli.synth.simplify import simplify_static

    lines = text.splitlines()
    head = [ln.replace(" x degree ", f" x {objective_term(objective)} ") for ln in lines if ln.startswith("#")]
    program = parse("\n".join(ln for ln in lines if not ln.startswith("#")))
    rounds, notes = [], []
    for r, rules in enumerate(program.rounds, start=1):
        simple, changed = simplify_static(rules, vocab(task, features))
        rounds.append(simple)
        notes += [f"round {r}, {n}" if program.n_rounds > 1 else n for n in changed]
    program = Program(tuple(rounds))
    said = ([f"Shown simplified (whatever the data; rules numbered as evaluated: {'; '.join(notes)}); the result file keeps the program as "
             "evaluated."] if notes else [])
    return "\n".join(head + [to_text(program).rstrip()]), program, said


def _has_program(metrics: dict) -> bool:
    """An evaluation of a baseline that runs under a program (prog, det-prog and their retrainings)."""
    return getattr(SCHEMES.get(metrics["baseline"]), "has_program", False)

DOCS = ROOT / "docs"
RESULTS = DOCS / "results"
TEMPLATE = DOCS / "results.template.md"
METRICS = ("cost", "max_in", "max_out", "max_degree", "mean_degree", "collisions")
ORDER = ["tf-full", "hard-attn", "dist", "prog", "prog-retrained", "det-prog", "det-prog-retrained", "dt",
         "dt-retrained", "no-comm"]

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


# ------------------------------------------------------------------------------------------------ collect
def draw_figures() -> None:
    """docs/figures/<task>.png (the paper's Figure 2 with a loss-vs-degree panel) from the result files alone."""
    from neurosym_cli.plotting import figure2

    for task in VARIANTS:
        f = RESULTS / f"{task}.json"
        if VARIANTS[task][0] != task or not f.exists():
            continue  # one figure per task, from its main variant
        r = json.loads(f.read_text())
        rows = [(r["baselines"][b]["label"], r["baselines"][b]["summary"]) for b in ORDER if b in r["baselines"]]
        title = f"{task} (paper budget, train seed 0): mean ± std over {r['seeds']} eval seeds"
        (DOCS / "figures").mkdir(exist_ok=True)
        figure2(rows, title.replace(": ", ":\n"), DOCS / "figures" / f"{task}.png")
        print(f"drew {DOCS / 'figures' / (task + '.png')}")


def collect(root: Path, budget: str = "paper", seed: int = 0) -> None:
    """The artifacts of the paper protocol under ``root`` -> one small JSON file per variant, run.json, figures."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    for name, (task, lam, objective) in VARIANTS.items():
        exp = root / task / budget / f"seed{seed}"
        out: dict = {"task": task, "objective": objective, "baselines": {}, "programs": {}}
        for f in sorted(exp.glob("eval/*/metrics.json")):
            m = json.loads(f.read_text())
            c = m["config"]
            if _has_program(m):
                if (c["lam"] != (c["task"]["lam"] if lam is None else lam) or c["synth"]["objective"] != objective
                        or not c["synth"].get("own_scores", True) or c.get("program")):
                    continue  # another variant's programs, or a hand-written one
                out["lam"], out["rules"], out["features"] = c["lam"], c["rules"], c["features"]
            out["baselines"][m["baseline"]] = {
                "label": m["label"],
                "summary": {k: {"mean": m["summary"][k]["mean"], "std": m["summary"][k]["std"]} for k in METRICS},
                "cost_per_seed": {str(r["seed"]): r["cost"] for r in m["per_seed"]},
            }
            out["seeds"] = m["seeds"]
        if "lam" not in out:
            print(f"no program evaluations for {name} under {exp}; skipped", file=sys.stderr)
            continue
        suffix = f"-lam{out['lam']:g}-{out['features']}" + ("" if objective == "paper" else f"-{objective}")
        for p in sorted(exp.glob("synth/*/program.txt")):
            if p.parent.name.endswith(suffix):
                out["programs"][p.parent.name] = p.read_text().strip()
        timing = exp / "pipeline_timings.json"
        if name == task and timing.exists():
            out["timings"] = json.loads(timing.read_text())
        (RESULTS / f"{name}.json").write_text(json.dumps(out, indent=1, sort_keys=True) + "\n")
        print(f"wrote {RESULTS / (name + '.json')}: {len(out['baselines'])} baselines")
    logs = root / "logs" / "paper"
    run = {}
    if (logs / "jobs.json").exists():
        jobs = json.loads((logs / "jobs.json").read_text())
        run["wall_min"] = jobs["wall_s"] / 60
        run["worker_min"] = sum(s or 0 for s in jobs["stages"].values()) / 60
    if (logs / "followups.json").exists():
        fol = json.loads((logs / "followups.json").read_text())
        run["followups_min"] = max(v["seconds"] for v in fol.values()) / 60
    (RESULTS / "run.json").write_text(json.dumps(run, indent=1, sort_keys=True) + "\n")


def collect_select(exp: Path) -> None:
    """<exp>/select/selection.json (and the pick's test evaluations) -> docs/results/select-<task>.json."""
    sel = json.loads((exp / "select" / "selection.json").read_text())
    keep = ("name", "lam", "rules", "features", "objective", "l1", "degree_term", "loss", "degree", "max_in",
            "max_out", "search_seconds")
    out = {k: sel[k] for k in ("task", "name", "rules", "lam", "features", "synth", "val_seeds", "grid",
                               "finalists", "seconds", "jobs", "rule")}
    out["programs"] = [{k: r.get(k) for k in keep} for r in sel["programs"]]
    out["retrained"] = [{k: r.get(k) for k in ("name", "loss", "degree", "max_in", "max_out")}
                        for r in sel["retrained"]]
    out["test"] = {}
    for f in sorted(exp.glob(f"eval/*-{sel['name']}/metrics.json")):
        m = json.loads(f.read_text())
        out["test"][m["baseline"]] = {
            "label": m["label"],
            "summary": {k: {"mean": m["summary"][k]["mean"], "std": m["summary"][k]["std"]} for k in METRICS},
            "cost_per_seed": {str(r["seed"]): r["cost"] for r in m["per_seed"]}}
    out["program"] = (exp / "synth" / sel["name"] / "program.txt").read_text().strip()
    path = RESULTS / f"select-{sel['task']}.json"
    path.write_text(json.dumps(out, indent=1, sort_keys=True) + "\n")
    print(f"wrote {path}")


def collect_stress(exp: Path) -> None:
    """<exp>/stress/stress.json -> docs/results/stress-<task>.json (without the config)."""
    st = json.loads((exp / "stress" / "stress.json").read_text())
    st.pop("config", None)
    cfg = json.loads((exp / "stress" / "stress.json").read_text())["config"]
    st.update(budget=cfg["budget"]["name"], seed=cfg["seed"], rules=cfg["rules"], lam=cfg["lam"],
              features=cfg["features"])
    path = RESULTS / f"stress-{st['task']}.json"
    path.write_text(json.dumps(st, indent=1, sort_keys=True) + "\n")
    print(f"wrote {path}")


def collect_rl(exp: Path) -> None:
    """<exp>/rl/grid.json, the picks' test evaluations and the training manifests -> docs/results/rl-<task>.json."""
    grid = json.loads((exp / "rl" / "grid.json").read_text())
    out = {k: grid[k] for k in ("task", "budget", "seed", "val_seeds", "rl1", "rl2", "rule", "settings", "seconds",
                                "jobs")}
    out["test"] = {}
    for label in ("rl1", "rl2"):
        m = json.loads((exp / "eval" / label / "metrics.json").read_text())
        out["test"][label] = {
            "label": label, "setting": grid[label]["name"],
            "summary": {k: {"mean": m["summary"][k]["mean"], "std": m["summary"][k]["std"]} for k in METRICS},
            "cost_per_seed": {str(r["seed"]): r["cost"] for r in m["per_seed"]}}
    out["extra"] = {}  # rl models evaluated outside the grid (a setting from scratch, too costly for the grid)
    names = {s["name"] for s in grid["settings"]}
    for f in sorted(exp.glob("eval/rl-*/metrics.json")):
        m = json.loads(f.read_text())
        if m["label"] in names:
            continue
        man = json.loads((exp / "train" / m["label"] / "manifest.json").read_text())
        out["extra"][m["label"]] = {
            "label": m["label"],
            "summary": {k: {"mean": m["summary"][k]["mean"], "std": m["summary"][k]["std"]} for k in METRICS},
            "cost_per_seed": {str(r["seed"]): r["cost"] for r in m["per_seed"]},
            "training": {k: man[k] for k in ("rollouts", "seconds_this_run", "rollouts_per_second", "final_loss")}}
    oracle = json.loads((exp / "train" / "oracle" / "manifest.json").read_text())
    out["oracle_training"] = {k: oracle[k] for k in ("rollouts", "seconds_this_run", "rollouts_per_second",
                                                      "final_loss")}
    path = RESULTS / f"rl-{grid['task']}.json"
    path.write_text(json.dumps(out, indent=1, sort_keys=True) + "\n")
    print(f"wrote {path}")


def rl(task: str, variants: dict[str, dict]) -> str:
    """The rl-<task>.json section (paper appendix D): the grid, the picks' test rows beside the main baselines and
    the selected program, and the paper's claims."""
    r = json.loads((RESULTS / f"rl-{task}.json").read_text())
    v = variants[task]
    sel_file = RESULTS / f"select-{task}.json"
    vs = with_selected(v, json.loads(sel_file.read_text())) if sel_file.exists() else v
    extra = r.get("extra", {})
    vs = {**vs, "baselines": {**vs["baselines"], **r["test"], **extra}}
    which = "selected" if sel_file.exists() else "default"
    out = [f"Grid: cost weight {sorted({s['cost'] for s in r['settings']})}, reward to go or whole episode, "
           f"from {sorted({s['init'] for s in r['settings']})} ({len(r['settings'])} settings), each trained for "
           f"{r['settings'][0]['rollouts']} rollouts on the oracle of the {task} section; {r['val_seeds']} "
           f"validation seeds; {r['jobs']} setting(s) trained at a time.", "",
           "| setting | cost weight | reward | val loss ± 95 % | max in | max out | max in+out | rollouts/s | pick |",
           "|---|---|---|---|---|---|---|---|---|"]
    for s in sorted(r["settings"], key=lambda s: s["val_loss"]):
        out.append(f"| {s['name']} | {s['cost']:g} | {'to go' if s['shaped'] else 'episode'} | "
                   f"{s['val_loss']:.2f} ± {s['val_loss_ci']:.2f} | {s['max_in']:.2f} | {s['max_out']:.2f} | "
                   f"{s['max_degree']:.2f} | {s['rollouts_per_second']:.1f} | {s['pick']} |")
    out += ["", f"Test seeds ({v['seeds']}, the same episodes as every table of this page; {EVAL_PM}):", "",
            "| baseline | loss | max in | max out | max in+out |", "|---|---|---|---|---|"]
    rows = [b for b in ("tf-full", "hard-attn", "dist", "prog-retrained", "no-comm") if b in vs["baselines"]]
    for b in rows + ["rl1", "rl2"] + sorted(extra):
        name = f"prog-retrained ({which} program)" if b == "prog-retrained" else \
            (f"**{b}** ({r['test'][b]['setting']})" if b in r["test"] else
             (f"{b} (outside the grid)" if b in extra else b))
        out.append(f"| {name} | {ms(vs, b, 'cost')} | {ms(vs, b, 'max_in')} | {ms(vs, b, 'max_out')} | "
                   f"{ms(vs, b, 'max_degree')} |")
    pr = "prog-retrained"
    d1, d2 = paired(vs, "rl1", pr), paired(vs, "rl2", pr)
    deg = {b: mean(vs, b, "max_degree") for b in ("rl1", "rl2", pr, "tf-full")}
    ok1 = deg["rl1"] > deg[pr]
    ok2 = d2[0] - d2[1] > 0
    dominated = [b for b in ("rl1", "rl2") if mean(vs, b) <= mean(vs, pr) and deg[b] <= deg[pr]]
    out += ["", "The paper's claims (appendix D):", "",
            f"- rl1 (the lowest loss over the settings) has a much higher degree than prog-retrained: max in+out "
            f"{deg['rl1']:.2f} vs {deg[pr]:.2f} (tf-full {deg['tf-full']:.2f}); its loss against prog-retrained: "
            f"{pm(d1)} (paired) -> {verdict(ok1)}",
            f"- rl2 (the lowest degree) has a much higher loss than prog-retrained: {mean(vs, 'rl2'):.2f} vs "
            f"{mean(vs, pr):.2f} (paired {pm(d2)}), at max in+out {deg['rl2']:.2f} -> {verdict(ok2)}",
            f"- the program does better than both: neither pick has both a loss and a degree at most "
            f"prog-retrained's -> {verdict(not dominated)}"
            + ("" if not dominated else f" ({', '.join(dominated)} does)")]
    t = r["oracle_training"]
    rl_rate = sum(s["rollouts_per_second"] for s in r["settings"]) / len(r["settings"])
    out += ["", f"Cost: an rl setting trained at {rl_rate:.1f} rollouts/s (mean over the settings, {r['jobs']} "
            f"one-thread job(s) at a time), the oracle's BPTT at {t['rollouts_per_second']:.1f} rollouts/s when it "
            f"was trained (one thread, another job beside it); from the oracle, a setting is "
            f"{r['settings'][0]['rollouts']} rollouts ({sum(s['train_seconds'] for s in r['settings']) / len(r['settings']) / 60:.1f} "
            f"min), the oracle itself {t['rollouts']} ({t['seconds_this_run'] / 60:.1f} min); docs/performance.md "
            "section 11."]
    for b, e in sorted(extra.items()):
        tr = e["training"]
        out += ["", f"Outside the grid, `{b}` trained from a fresh transformer for the oracle's whole budget "
                f"({tr['rollouts']} rollouts in {tr['seconds_this_run'] / 60:.1f} min, {tr['rollouts_per_second']:.1f} "
                f"rollouts/s, final training loss {tr['final_loss']:.2f} against the oracle's "
                f"{t['final_loss']:.2f}); on the test seeds: loss {mean(vs, b):.2f} (against tf-full {pm(paired(vs, b, 'tf-full'))}, "
                f"paired) at max in+out {mean(vs, b, 'max_degree'):.2f}."]
    return "\n".join(out)


def collect_noisy(exp: Path) -> None:
    """Appendix E: every test evaluation of a link-failure run directory (where `neurosym pipeline selected=true`
    ran) -> docs/results/<task>.json, the variant format, programs of the selected configuration only."""
    sel = json.loads((exp / "select" / "selected.json").read_text())
    out: dict = {"task": sel["task"], "objective": "paper", "baselines": {}, "programs": {}, "rules": sel["rules"],
                 "lam": sel["lam"], "features": sel["features"]}
    for f in sorted(exp.glob("eval/*/metrics.json")):
        m = json.loads(f.read_text())
        if _has_program(m) and not m["label"].endswith("-" + sel["name"]):
            continue  # programs of other configurations
        out["baselines"][m["baseline"]] = {
            "label": m["label"],
            "summary": {k: {"mean": m["summary"][k]["mean"], "std": m["summary"][k]["std"]} for k in METRICS},
            "cost_per_seed": {str(r["seed"]): r["cost"] for r in m["per_seed"]}}
        out["seeds"] = m["seeds"]
        out["link_failure"] = m["config"]["task"]["link_failure"]
    out["programs"][sel["name"]] = (exp / "synth" / sel["name"] / "program.txt").read_text().strip()
    path = RESULTS / f"{sel['task']}.json"
    path.write_text(json.dumps(out, indent=1, sort_keys=True) + "\n")
    print(f"wrote {path}: {len(out['baselines'])} baselines")


def noisy(task: str, clean: str) -> str:
    """Appendix E: the baselines under link failure, the selection's best program per K, the paper's claims (the
    pick's K against the one ``clean``'s selection made without failures)."""
    from neurosym_cli.stages.select import choose

    v = json.loads((RESULTS / f"{task}.json").read_text())
    sel = json.loads((RESULTS / f"select-{task}.json").read_text())
    sel_clean = json.loads((RESULTS / f"select-{clean}.json").read_text())
    pr = "prog-retrained"
    out = [f"Every directed link fails with probability {v['link_failure']:g} at every step, in training, "
           f"retraining and evaluation, for every baseline. The programs are the pick of `neurosym select` on this "
           f"task's oracle (K = {sel['rules']}, lambda = {sel['lam']:g}, {sel['features']}); {v['seeds']} test "
           f"seeds; degrees count the messages delivered. Loss and degrees: {EVAL_PM}.", "",
           "| baseline | loss | max in | max out | max in+out |", "|---|---|---|---|---|"]
    for b in ORDER:
        if b in v["baselines"]:
            out.append(f"| {b} | {ms(v, b, 'cost')} | {ms(v, b, 'max_in')} | {ms(v, b, 'max_out')} | "
                       f"{ms(v, b, 'max_degree')} |")
    first = choose(sel["programs"])
    out += ["", "The selection by K: the best program of each K on the validation seeds (prog, the oracle under "
            "it), over the lambdas and feature maps of the grid:", "",
            "| K | best program | val loss ± 95 % | Δ to the best ± 95 % | max in+out | similar to the best |",
            "|---|---|---|---|---|---|"]
    for k in sorted({r["rules"] for r in first}):
        r = min((r for r in first if r["rules"] == k), key=lambda r: r["loss_mean"])
        out.append(f"| {k} | {r['name'].split('-coarse')[0]} | {r['loss_mean']:.2f} ± {r['loss_ci']:.2f} | "
                   f"{r['diff']:+.2f} ± {r['diff_ci']:.2f} | {r['degree']:.2f} | {'yes' if r['similar'] else 'no'} |")
    best = next(r for r in first if r["best"])
    text, program, said = shown(sel["program"], sel["task"], sel["features"])
    kept = len(program.rounds[0])
    out += ["", f"The selected program (searched with K = {sel['rules']}; {kept} rules left after simplification "
            "dropped those that never fire on D):", "", "```", text, "```", "", *([*said, ""] if said else [])]
    for rules in program.rounds:
        out += [f"- rule {k}: {describe(rule, vocab(sel['task'], sel['features']))}"
                for k, rule in enumerate(rules, start=1)]
    g, d = gap(v, pr, "tf-full"), paired(v, pr, "tf-full")
    ok1 = abs(g) <= 5 and mean(v, pr, "max_degree") < mean(v, "tf-full", "max_degree")
    ok2 = sel["rules"] == 4
    if "no-comm" in v["baselines"]:
        def vs_none(b: str) -> str:
            return f"{gap(v, b, 'no-comm'):+.1f} %".replace("-", "−")

        out += ["", f"What communication is worth here: no-comm {mean(v, 'no-comm'):.2f}, tf-full "
                f"{vs_none('tf-full')} against it (paired {pm(paired(v, 'tf-full', 'no-comm'))}), prog-retrained "
                f"{vs_none(pr)} (paired {pm(paired(v, pr, 'no-comm'))}), hard-attn {vs_none('hard-attn')}, dist "
                f"{vs_none('dist')}."]
    out += ["", "The paper's claims (appendix E):", "",
            f"- prog-retrained has a loss similar to tf-full (within 5 %) with a lower degree: {mean(v, pr):.2f} vs "
            f"{mean(v, 'tf-full'):.2f}, {g:+.1f} % (paired {pm(d)}); max in+out {mean(v, pr, 'max_degree'):.2f} vs "
            f"{mean(v, 'tf-full', 'max_degree'):.2f} -> {verdict(ok1)}",
            f"- the best policy has four rules, against two without failures: the pick was searched with K = "
            f"{sel['rules']} and keeps {kept} rules (the validation-best program K = {best['rules']}); on {clean} "
            f"without failures our selection picked K = {sel_clean['rules']} -> {verdict(ok2)}"
            + ("" if ok2 else f"; more rules than without failures: searched with K = {sel['rules']} against "
               f"{sel_clean['rules']}, and {kept} rules kept against {len(parse(sel_clean['program']).rounds[0])}")]
    return "\n".join(out)


def _stress_cfg(st: dict):
    """What plotting.stress_plot reads of a config, from a stress result file."""
    from types import SimpleNamespace as NS

    return NS(rules=st["rules"], seed=st["seed"], task=NS(name=st["task"], agents_per_group=st["trained_agents_per_group"]),
              budget=NS(name=st["budget"]), stress=NS(seeds=st["seeds"]))


def draw_stress(task: str) -> None:
    from neurosym_cli.plotting import stress_plot

    f = RESULTS / f"stress-{task}.json"
    if f.exists():
        st = json.loads(f.read_text())
        stress_plot(st["results"], _stress_cfg(st), DOCS / "figures" / f"{task}-stress.png")
        print(f"drew {DOCS / 'figures' / (task + '-stress.png')}")


VMAS_METRICS = METRICS + ("on_goal", "covered", "success")
VMAS_COMMAND = ("neurosym pipeline task={task} budget=vmas threads=1 plots=false "
                "\"baselines=[tf-full,hard-attn,dist,prog,prog-retrained,expo,comm-range,no-comm]\" "
                "baseline=comm-range baseline.radius=0.5")


def collect_vmas(exp: Path, wall: float | None = None) -> None:
    """A VMAS scenario's run directory (docs/vmas.md, 'Results') -> docs/results/vmas-<scenario>.json: every
    baseline's summary (mean, std, 95 % t half-width over the evaluation seeds) and per-seed losses, the program,
    each trained model's training (loss every 10 steps, seconds), the stage times and the measured wall time."""
    out: dict = {"baselines": {}, "training": {}}
    for f in sorted(exp.glob("eval/*/metrics.json")):
        m = json.loads(f.read_text())
        c = m["config"]
        out.update(task=f"vmas/{c['task']['name'].removeprefix('vmas-')}", seeds=m["seeds"],
                   episodes_per_seed=m["episodes_per_seed"], training_seed=c["seed"], budget=c["budget"],
                   horizon=c["task"]["horizon"], comm_range_radius=0.5)
        out["baselines"][m["baseline"]] = {
            "label": m["label"],
            "summary": {k: {x: m["summary"][k][x] for x in ("mean", "std", "ci95")} for k in VMAS_METRICS
                        if k in m["summary"]},
            "cost_per_seed": {str(r["seed"]): r["cost"] for r in m["per_seed"]}}
        if _has_program(m):
            out["program"] = (exp / "synth" / m["label"].removeprefix(m["baseline"] + "-") / "program.txt"
                              ).read_text().strip()
    for f in sorted(exp.glob("train/*/manifest.json")):
        man = json.loads(f.read_text())
        with open(f.parent / "history.csv") as h:
            losses = [float(r["loss"]) for r in csv.DictReader(h)]
        out["training"][f.parent.name] = {
            "steps": len(losses), "rollouts": man["rollouts"], "seconds": round(man["seconds_this_run"], 1),
            "loss_every_10_steps": [round(sum(losses[i:i + 10]) / len(losses[i:i + 10]), 3)
                                    for i in range(0, len(losses), 10)]}
    out["command"] = VMAS_COMMAND.format(task=out["task"])
    out["stage_seconds"] = json.loads((exp / "pipeline_timings.json").read_text())
    if wall is not None:
        out["wall_seconds"] = wall
    path = RESULTS / f"vmas-{out['task'].split('/')[-1]}.json"
    path.write_text(json.dumps(out, indent=1, sort_keys=True) + "\n")
    print(f"wrote {path}: {len(out['baselines'])} baselines")
    heard = {e["label"]: e["summary"]["max_in"]["mean"] for e in out["baselines"].values()}
    for gif in sorted(exp.glob("render/*/episode0.gif")):  # what `neurosym render ... episode=0` drew
        if heard.get(gif.parent.name):  # an episode without edges says nothing about whom agents hear
            vmas_episode_figures(gif, DOCS / "figures" / f"{path.stem}-{gif.parent.name}-episode0")


def vmas_episode_figures(gif: Path, stem: Path, frames: int = 4) -> None:
    """`neurosym render`'s animation -> <stem>.gif (a copy) and <stem>.png: ``frames`` of its frames in a 2-column
    grid (the start, evenly spaced steps, the end), each with the edges used at that step."""
    import shutil

    from PIL import Image

    gif_out, png_out = Path(f"{stem}.gif"), Path(f"{stem}.png")  # labels hold dots (lam0.5): no with_suffix
    shutil.copyfile(gif, gif_out)
    with Image.open(gif) as im:
        picks = [round(k * (im.n_frames - 1) / (frames - 1)) for k in range(frames)]
        shots = []
        for k in picks:
            im.seek(k)
            shots.append(im.convert("RGB"))
    w, h, cols = max(x.width for x in shots), max(x.height for x in shots), 2  # a 2-column grid stays readable
    grid = Image.new("RGB", (cols * w, -(-len(shots) // cols) * h), "white")
    for k, x in enumerate(shots):
        grid.paste(x, ((k % cols) * w, (k // cols) * h))
    grid.save(png_out)
    print(f"drew {png_out} (frames {picks} of {gif})")


def draw_vmas() -> None:
    """docs/figures/vmas-<scenario>.png (loss, degrees, loss against max in-degree; 95 % t intervals over the
    evaluation seeds) from the VMAS result files alone."""
    from neurosym_cli.plotting import figure2

    for f in sorted(RESULTS.glob("vmas-*.json")):
        r = json.loads(f.read_text())
        b = r["baselines"]
        rows = [(b[k]["label"], b[k]["summary"]) for k in _vmas_order(b)]
        title = (f"{r['task']} ({r['budget']['name']} budget, train seed {r['training_seed']}): "
                 f"mean ± 95 % t interval over {r['seeds']} eval seeds")
        figure2(rows, title.replace(": ", ":\n"), DOCS / "figures" / f"{f.stem}.png", err="ci95")
        print(f"drew {DOCS / 'figures' / (f.stem + '.png')}")


def _vmas_order(b: dict) -> list[str]:
    return sorted(b, key=lambda k: (ORDER.index(k) if k in ORDER else len(ORDER), k))


def vmas(task: str) -> str:
    """A VMAS scenario's run (docs/results/vmas-<scenario>.json, written by --collect-vmas): the table with the 95 %
    t interval over the evaluation seeds, the loss-degree figure, the program with its reading, the rendered
    episode, the training, and the paper's claims checked the same way as on its tasks (paired differences)."""
    name = f"vmas-{task.split('/')[-1]}"
    f = RESULTS / f"{name}.json"
    if not f.exists():
        return f"Not yet run: no result file `{f.relative_to(DOCS)}`."
    v = json.loads(f.read_text())
    b = v["baselines"]
    extra = [m for m in ("on_goal", "covered", "success", "collisions") if m in b["tf-full"]["summary"]]
    out = [f"`{v['command']}` (training seed {v['training_seed']}; {v['seeds']} evaluation seeds of "
           f"{v['episodes_per_seed']} episodes, T = {v['horizon']}). Loss and degrees: mean ± 95 % Student-t "
           "interval over the evaluation seeds of this one trained model; the scenario's own metrics: means.", "",
           "| baseline | loss | max in | max out | " + " | ".join(extra) + " |",
           "|---|---:|---:|---:|" + "---:|" * len(extra)]
    for k in _vmas_order(b):
        sm = b[k]["summary"]
        ci = lambda m: f"{sm[m]['mean']:.2f} ± {sm[m]['ci95']:.2f}"  # noqa: E731
        out.append(f"| {b[k]['label']} | {ci('cost')} | {ci('max_in')} | {ci('max_out')} | "
                   + " | ".join(f"{sm[e]['mean']:.3f}" for e in extra) + " |")
    if (DOCS / "figures" / f"{name}.png").exists():
        out += ["", f"![{task}: loss vs max in+out](figures/{name}.png)"]
    text, program, said = shown(v["program"], task, "v1")
    out += ["", "The synthesized program (`neurosym show-program` prints it as evaluated):", "", "```", text, "```", "",
            *([*said, ""] if said else [])]
    for rules in program.rounds:
        out += [f"- rule {k}: {describe(rule, vocab(task, 'v1'))}" for k, rule in enumerate(rules, start=1)]
    labels = {b[k]["label"]: k for k in b}
    shots = [p for p in sorted((DOCS / "figures").glob(f"{name}-*-episode0.png"))
             if p.name.removeprefix(f"{name}-").removesuffix("-episode0.png") in labels]
    if b["prog-retrained"]["summary"]["max_in"]["mean"] == 0:
        out += ["", "The program hears nobody, so an episode under prog-retrained has no edges to draw; the "
                "hard-attn episode shows whom the oracle itself picks (its K = 2 largest attention logits)."]
    for png in shots:
        label = png.name.removeprefix(f"{name}-").removesuffix("-episode0.png")
        gif = png.with_suffix(".gif")
        out += ["", f"Evaluation episode 0 under {label} at its start, two evenly spaced steps and its end, each "
                f"frame with the edges used at that step (`neurosym render task={task} budget=vmas "
                f"baseline={labels[label]} episode=0`" + (f"; animated: [{gif.name}](figures/{gif.name})"
                                                         if gif.exists() else "") + "):", "",
                f"![{task}: episode 0 under {label}](figures/{png.name})"]
    tr = v["training"]
    out += ["", "Training loss, mean over each 10 optimizer steps of 8 episodes (the same episodes for every model):",
            "", "| model | steps | seconds | loss every 10 steps |", "|---|---:|---:|---|"]
    out += [f"| {k} | {t['steps']} | {t['seconds']:.0f} | {' '.join(f'{x:.2f}' for x in t['loss_every_10_steps'])} |"
            for k, t in sorted(tr.items())]
    total = sum(v["stage_seconds"].values())
    wall = v.get("wall_seconds", total)
    verbs: dict[str, list[float]] = {}
    for stage, sec in v["stage_seconds"].items():
        verbs.setdefault(stage.split()[0], []).append(sec)
    out += ["", f"Wall time: {wall / 60:.1f} min for the pipeline on one thread of the busy 2-core machine ("
            + ", ".join(f"{verb} {sum(x):.0f} s over {len(x)} stage{'s' * (len(x) > 1)}" for verb, x in verbs.items())
            + ")."]
    return "\n".join(out + ["", "Claims of the paper, checked the same way as on its tasks (paired differences "
                             "over the evaluation seeds, 95 % t interval):", ""]
                     + [f"- {line}" for line in vmas_claims(v)])


def vmas_claims(v: dict) -> list[str]:
    """The paper's claims on a VMAS run, each line with its numbers and its verdict; failures stay in, with why."""
    pr, b = "prog-retrained", v["baselines"]
    lines = []

    def lower(a: str, than: str, what: str) -> bool:
        d = paired(v, a, than)
        ok = d[0] + d[1] < 0
        note = "" if ok else (" (lower on average, not significant)" if d[0] < 0 else "")
        lines.append(f"{what}: {mean(v, a):.3f} vs {mean(v, than):.3f} (paired difference {pm(d, 3)}){note} -> "
                     f"{verdict(ok)}")
        return ok

    comm = lower("tf-full", "no-comm", "communication matters (tf-full below no-comm)")
    g, d = gap(v, pr, "tf-full"), paired(v, pr, "tf-full")
    lines.append(f"prog-retrained close to tf-full (within 5 %): {mean(v, pr):.3f} vs {mean(v, 'tf-full'):.3f}, "
                 f"{g:+.1f} % (paired difference {pm(d, 3)}) -> {verdict(abs(g) <= 5)}")
    lower(pr, "dist", "prog-retrained better than dist")
    lower(pr, "no-comm", "prog-retrained below no-comm")
    d = paired(v, "prog", pr)
    lines.append(f"retraining is needed (prog worse than prog-retrained): {mean(v, 'prog'):.3f} vs {mean(v, pr):.3f} "
                 f"(paired difference {pm(d, 3)}) -> {verdict(d[0] - d[1] > 0)}")
    for m, words, other in (("max_out", "max out", "hard-attn"), ("max_degree", "max in+out", "tf-full")):
        lines.append(f"prog-retrained {words} lower than {other}: {ms(v, pr, m)} vs "
                     f"{ms(v, other, m)} (mean ± 95 % t half-width) -> {verdict(mean(v, pr, m) < mean(v, other, m))}")
    for other in ("expo", "comm-range"):  # beyond the paper: the topologies VMAS users have (ExpoComm, BenchMARL)
        if other in b:
            lower(pr, other, f"beyond the paper: prog-retrained better than {b[other]['label']}")
    d = paired(v, "tf-full", "no-comm")
    if d[0] - d[1] > 0:
        lines.append("here hearing nobody is better than hearing everybody: at this budget the oracle has not learned "
                     "to gain from what it hears (its training loss never went below no-comm's, table above), so "
                     "the claims about the program compare sparse models against an oracle worse than silence "
                     "(docs/vmas.md, 'Results').")
    elif not comm:
        silent = b[pr]["summary"]["max_in"]["mean"] == 0
        lines.append("where hearing nobody is as good as hearing everybody, the claims about the program say little "
                     "about the method" + (": the search's best program is then the silent one" if silent else "")
                     + ", and every comparison is within the noise of this small budget (docs/vmas.md, 'Results').")
    return lines


def stress(task: str) -> str:
    """The stress-<task>.json section: one table per axis (loss / max in / max out per baseline), the figure."""
    st = json.loads((RESULTS / f"stress-{task}.json").read_text())
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
    if (DOCS / "figures" / f"{task}-stress.png").exists():
        out.append(f"![{task}: zero-shot stress](figures/{task}-stress.png)")
    return "\n".join(out).rstrip("\n")


def with_selected(v: dict, sel: dict) -> dict:
    """Variant ``v`` with its prog and prog-retrained replaced by the selected program's test evaluations."""
    out = {**v, "baselines": {**v["baselines"], **sel["test"]}, "rules": sel["rules"], "lam": sel["lam"],
           "features": sel["features"]}
    return out


def selection(task: str, variants: dict[str, dict]) -> str:
    """The select-<task>.json section: ranked table, pick, test numbers, claims with the pick, Pareto figure."""
    from neurosym_cli.stages.select import choose

    sel = json.loads((RESULTS / f"select-{task}.json").read_text())
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
    for r, rules in enumerate(program.rounds, start=1):
        head = f"round {r}, " if program.n_rounds > 1 else ""
        out += [f"- {head}rule {k}: {describe(rule, vocab(sel['task'], sel['features']))}"
                for k, rule in enumerate(rules, start=1)]
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
    for short, long, _, ok, *_ in claims(task, vs):
        if "det-prog" in short:  # its programs were searched with the default lambda and features, not the pick's
            out.append(f"- {short}: not re-checked (det-prog was not searched with the picked lambda and features)")
            continue
        change = "" if before.get(short) == ok else f" (with the default configuration: {verdict(before[short])})"
        out.append(f"- {long} -> {verdict(ok)}{change}")
    if (DOCS / "figures" / f"{task}-pareto-selected.png").exists():
        out += ["", f"![{task}: loss against max in+out, Pareto front](figures/{task}-pareto-selected.png)"]
    return "\n".join(out)


def draw_pareto(task: str) -> None:
    """docs/figures/<task>-pareto-selected.png: loss vs max in+out of every baseline and the selected program."""
    from neurosym_cli.plotting import pareto_plot
    from neurosym_cli.utils.pareto import dominated_area, pareto_front

    f = RESULTS / f"select-{task}.json"
    if not f.exists():
        return
    sel = json.loads(f.read_text())
    v = json.loads((RESULTS / f"{task}.json").read_text())
    pts = [(v["baselines"][b]["label"], v["baselines"][b]["summary"]["max_degree"]["mean"],
            v["baselines"][b]["summary"]["cost"]["mean"]) for b in ORDER if b in v["baselines"]]
    pts += [(f"{b}-{sel['name'].split('-coarse')[0]} (selected)", m["summary"]["max_degree"]["mean"],
             m["summary"]["cost"]["mean"]) for b, m in sel["test"].items()]
    rl_file = RESULTS / f"rl-{task}.json"
    if rl_file.exists():  # the appendix-D picks, on the same test seeds
        pts += [(b, m["summary"]["max_degree"]["mean"], m["summary"]["cost"]["mean"])
                for b, m in json.loads(rl_file.read_text())["test"].items()]
    xy = [(d, c) for _, d, c in pts]
    front = pareto_front(xy)
    ref = (1.05 * max(x for x, _ in xy), 1.05 * max(y for _, y in xy))
    pareto_plot(pts, front, ref, dominated_area([xy[i] for i in front], ref),
                f"{task} (paper budget, train seed 0): test loss against max in+out (lower left is better),\n"
                "every baseline, the program chosen by `neurosym select`"
                + (" and the rl picks of `neurosym rl`" if rl_file.exists() else ""),
                DOCS / "figures" / f"{task}-pareto-selected.png")
    print(f"drew {DOCS / 'figures' / (task + '-pareto-selected.png')}")


# ------------------------------------------------------------------------------------------------- render
def load() -> tuple[dict[str, dict], dict]:
    variants = {n: json.loads((RESULTS / f"{n}.json").read_text()) for n in VARIANTS if (RESULTS / f"{n}.json").exists()}
    run = json.loads((RESULTS / "run.json").read_text()) if (RESULTS / "run.json").exists() else {}
    return variants, run


def mean(v: dict, b: str, k: str = "cost") -> float:
    return v["baselines"][b]["summary"][k]["mean"]


EVAL_PM = "mean ± 95 % Student-t half-width over the evaluation seeds (the episode noise of one trained model)"
"""what ± means in every table of one training seed's evaluation (``ms``)"""


def ms(v: dict, b: str, k: str, digits: int = 2) -> str:
    """A baseline's metric over the evaluation seeds as the tables write it: mean ± 95 % t half-width (EVAL_PM)."""
    s = v["baselines"][b]["summary"][k]
    half = t95(v["seeds"]) * s["std"] / v["seeds"] ** 0.5
    return f"{s['mean']:.{digits}f} ± {half:.{digits}f}"


def paired(v: dict, a: str, b: str) -> tuple[float, float]:
    """Mean and 95% half-width of a - b over the evaluation seeds both share."""
    xa, xb = v["baselines"][a]["cost_per_seed"], v["baselines"][b]["cost_per_seed"]
    return mean_ci([xa[s] - xb[s] for s in sorted(set(xa) & set(xb), key=int)])


def pm(x: tuple[float, float], digits: int = 2) -> str:
    """A paired difference as the document writes it: signed, with a true minus sign."""
    return f"{x[0]:+.{digits}f} ± {x[1]:.{digits}f}".replace("-", "−")


def gap(v: dict, a: str, b: str) -> float:
    return (mean(v, a) - mean(v, b)) / mean(v, b) * 100


def verdict(ok: bool) -> str:
    return "**supported**" if ok else "**not supported**"


class Claim(NamedTuple):
    """One claim of the paper checked on one set of numbers: its short and long lines, its glance cell, whether it
    holds, its name (the short line without numbers: the same on every seed), and the quantity the verdict reads
    (``value``, described by ``unit``)."""

    short: str
    long: str
    cell: str
    holds: bool
    name: str
    value: float
    unit: str


def claims(task: str, v: dict) -> list[Claim]:
    """Each claim of the paper on this task, checked on the numbers of ``v`` (one training seed)."""
    pr = "prog-retrained"
    out = []
    if task in FORMATION:
        g, d = gap(v, pr, "tf-full"), paired(v, pr, "tf-full")
        out.append(Claim("prog-retrained loss close to tf-full (within 5 %)",
                         f"prog-retrained loss close to tf-full (within 5%): {mean(v, pr):.2f} vs "
                         f"{mean(v, 'tf-full'):.2f}, {g:+.1f}% (paired difference {d[0]:+.2f} ± {d[1]:.2f})",
                         f"{g:+.1f} %".replace("-", "−"), abs(g) <= 5, "prog-retrained loss close to tf-full (within 5 %)", g,
                         "% loss gap to tf-full"))
        d = paired(v, pr, "dist")
        ok = d[0] + d[1] < 0
        out.append(Claim("prog-retrained better than dist",
                         f"prog-retrained better than dist: {mean(v, pr):.2f} vs {mean(v, 'dist'):.2f} (paired "
                         f"difference {d[0]:+.2f} ± {d[1]:.2f})"
                         + ("" if ok else (" (lower on average, not significant)" if d[0] < 0 else "")),
                         pm(d) + ("" if ok else ", not significant" if d[0] < 0 else ""), ok, "prog-retrained better than dist",
                         d[0], "loss difference to dist"))
        dv = mean(v, pr, "max_out") - mean(v, "hard-attn", "max_out")
        out.append(Claim("prog-retrained max out-degree lower than hard-attn",
                         f"prog-retrained max out-degree lower than hard-attn: {ms(v, pr, 'max_out')} vs "
                         f"{ms(v, 'hard-attn', 'max_out')}",
                         f"{mean(v, pr, 'max_out'):.1f} vs {mean(v, 'hard-attn', 'max_out'):.1f}", dv < 0,
                         "prog-retrained max out-degree lower than hard-attn", dv, "max out-degree difference to hard-attn"))
        d = paired(v, "prog", pr)
        ok = d[0] - d[1] > 0
        out.append(Claim("retraining is needed (prog worse than prog-retrained)",
                         f"retraining is needed (prog worse than prog-retrained): {mean(v, 'prog'):.2f} vs "
                         f"{mean(v, pr):.2f} (paired difference {d[0]:+.2f} ± {d[1]:.2f})"
                         + ("" if ok else (" (worse on average, not significant)" if d[0] > 0 else "")),
                         f"{mean(v, 'prog'):.1f} vs {mean(v, pr):.1f}", ok, "retraining is needed (prog worse than prog-retrained)", d[0],
                         "loss of prog minus prog-retrained"))
        dv = mean(v, "det-prog-retrained", "max_out") - mean(v, pr, "max_out")
        out.append(Claim("det-prog-retrained has a worse max out-degree",
                         f"det-prog-retrained has a worse max out-degree than prog-retrained: "
                         f"{ms(v, 'det-prog-retrained', 'max_out')} vs {ms(v, pr, 'max_out')}",
                         f"{mean(v, 'det-prog-retrained', 'max_out'):.2f} vs {mean(v, pr, 'max_out'):.2f}", dv > 0,
                         "det-prog-retrained has a worse max out-degree", dv, "max out-degree difference det-prog-retrained minus "
                         "prog-retrained"))
        dv = max(mean(v, "dt", "max_in") - mean(v, pr, "max_in"), mean(v, "dt", "max_out") - mean(v, pr, "max_out"))
        out.append(Claim("dt has poor degrees",
                         f"dt has poor degrees: max in {ms(v, 'dt', 'max_in')}, max out {ms(v, 'dt', 'max_out')} vs "
                         f"prog-retrained {ms(v, pr, 'max_in')}, {ms(v, pr, 'max_out')}",
                         f"in {mean(v, 'dt', 'max_in'):.1f} / out {mean(v, 'dt', 'max_out'):.1f} vs "
                         f"{mean(v, pr, 'max_in'):.1f} / {mean(v, pr, 'max_out'):.1f}", dv > 0, "dt has poor degrees", dv,
                         "larger of dt's max in- and out-degree excess over prog-retrained"))
        return out
    m = mean(v, pr)
    out.append(Claim("prog-retrained well below 4.13 uncovered goals",
                     f"prog-retrained well below 4.13 uncovered goals (the paper's no-communication loss): "
                     f"{ms(v, pr, 'cost', 3)}", f"{m:.2f}", m < 0.9 * 4.13, "prog-retrained well below 4.13 uncovered goals", m,
                     "prog-retrained loss (uncovered goals)"))
    d = paired(v, pr, "no-comm")
    ok = d[0] + d[1] < 0
    out.append(Claim(f"... and below our own no-comm ({mean(v, 'no-comm'):.2f})",
                     f"... and below our own no-comm model ({ms(v, 'no-comm', 'cost', 3)}; paired difference "
                     f"{d[0]:+.3f} ± {d[1]:.3f})", pm(d) + ("" if ok else ", not significant"), ok,
                     "... and below our own no-comm",
                     d[0], "loss difference to no-comm"))
    g, d = gap(v, pr, "tf-full"), paired(v, pr, "tf-full")
    out.append(Claim(f"prog-retrained close to tf-full ({mean(v, 'tf-full'):.2f}, within 10 %)",
                     f"prog-retrained close to tf-full (within 10%): {mean(v, pr):.3f} vs {mean(v, 'tf-full'):.3f}, "
                     f"{g:+.1f}% (paired difference {d[0]:+.3f} ± {d[1]:.3f})",
                     f"{g:+.1f} % ({pm(d, 3)})".replace("-", "−"), abs(g) <= 10,
                     "prog-retrained close to tf-full (within 10 %)", g,
                     "% loss gap to tf-full"))
    dv = mean(v, pr, "max_degree") - mean(v, "tf-full", "max_degree")
    out.append(Claim("prog-retrained has a smaller max in+out than tf-full",
                     f"prog-retrained has a smaller max in+out than tf-full: {ms(v, pr, 'max_degree')} vs "
                     f"{ms(v, 'tf-full', 'max_degree')}",
                     f"{mean(v, pr, 'max_degree'):.1f} vs {mean(v, 'tf-full', 'max_degree'):.0f}", dv < 0,
                     "prog-retrained has a smaller max in+out than tf-full", dv, "max in+out difference to tf-full"))
    return out


def title(name: str, v: dict) -> str:
    _, lam, objective = VARIANTS[name]
    if lam is None and objective == "paper":
        return v["task"]
    return f"{v['task']} (programs: lambda {v['lam']:g}, {objective} objective)"


def section(name: str, v: dict) -> str:
    task = v["task"]
    out = [f"## {title(name, v)}", "", f"K = {v['rules']}, lambda = {v['lam']:g}, objective {v['objective']}, "
           f"{v['seeds']} evaluation seeds; loss and degrees: {EVAL_PM}.", "",
           "| baseline | loss | max in | max out | mean in+out |", "|---|---|---|---|---|"]
    digits = 3 if task == "unlabeled-goals" else 2
    for b in sorted(v["baselines"], key=lambda b: ORDER.index(b) if b in ORDER else len(ORDER)):
        out.append(f"| {b} | {ms(v, b, 'cost', digits)} | {ms(v, b, 'max_in')} | {ms(v, b, 'max_out')} | "
                   f"{ms(v, b, 'mean_degree')} |")
    if name == task and (DOCS / "figures" / f"{task}.png").exists():
        out += ["", f"![{task}: loss vs max in-degree](figures/{task}.png)"]
    out += ["", "Synthesized programs, each rule with its reading (`neurosym show-program` prints the same):", ""]
    for tag, raw in sorted(v["programs"].items()):
        text, program, said = shown(raw, v["task"], v["features"], v["objective"])
        out += [f"`{tag}`:", "", "```", text, "```", "", *([*said, ""] if said else [])]
        for r, rules in enumerate(program.rounds, start=1):
            head = f"round {r}, " if program.n_rounds > 1 else ""
            out += [f"- {head}rule {k}: {describe(rule, vocab(v['task'], v['features']))}"
                    for k, rule in enumerate(rules, start=1)]
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
    for family, names in (("paper section 4", [n for n in variants if variants[n]["task"] in FORMATION]),
                          ("unlabeled-goals", [n for n in variants if variants[n]["task"] == "unlabeled-goals"])):
        if not names:
            continue
        cols = [f"{variants[n]['task']} (λ {variants[n]['lam']:g}"
                + (", hinge objective)" if variants[n]["objective"] == "hinge" else ")") for n in names]
        rows = [claims(variants[n]["task"], variants[n]) for n in names]
        out += [f"| claim ({family}) | " + " | ".join(cols) + " |", "|---" * (len(cols) + 1) + "|"]
        for k, (short, *_rest) in enumerate(rows[0]):
            cells = [("yes, " if r[k][3] else "**no**: ") + r[k][2] for r in rows]
            out.append(f"| {short} | " + " | ".join(cells) + " |")
        out.append("")
    return "\n".join(out)


# ------------------------------------------------------------------------------------------ training seeds
SEEDS = RESULTS / "seeds"
SEED_TASKS = ("random-cross", "random-grid", "unlabeled-goals")
PLANNED_SEEDS = (0, 1, 2)
"""the training seeds the protocol runs per task (benchmarks/run_seeds.py)"""


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
    pct = " %" if unit.startswith("%") else ""
    sign = "" if unit.startswith("prog-retrained loss") else "+"  # a loss itself, not a difference: unsigned
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
    if (DOCS / "figures" / f"seeds-{task}.png").exists():
        out += ["", f"![{task}: loss against max in+out over training seeds, one marker per seed and the across-seed "
                f"mean ± 95 % t-interval](figures/seeds-{task}.png)"]
    return "\n".join(out)


def seeds_section(by_task: dict) -> str:
    """{{seeds}}: every task of SEED_TASKS over its training seeds, then the performance profile when drawn."""
    parts = [seeds_task(t, by_task.get(t, [])) for t in SEED_TASKS]
    if (DOCS / "figures" / "seeds-profile.png").exists():
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


def draw_seed_figures(by_task: dict, out_dir: Path = DOCS / "figures") -> None:
    """seeds-<task>.png and seeds-profile.png from the seed files alone (neurosym_cli.seeds.draw)."""
    from neurosym_cli import seeds

    for f in seeds.draw({t: r for t, r in by_task.items() if r}, out_dir):
        print(f"drew {f}")


def render(template: str, variants: dict[str, dict], run: dict, seed_runs: dict | None = None) -> str:
    """The page: every placeholder of ``template`` replaced (``seed_runs``: the seed files by task, read from
    docs/results/seeds when None)."""
    by_task = load_seeds() if seed_runs is None and "{{seeds" in template else (seed_runs or {})

    def fmt(x: float, digits: str) -> str:
        return f"{x:.{int(digits)}f}".replace("-", "−")

    ops = {
        "section": lambda n: section(n, variants[n]).rstrip("\n"),
        "glance": lambda: glance(variants).rstrip("\n"),
        "mean": lambda n, b, m, d: fmt(mean(variants[n], b, m), d),
        "half": lambda n, b, m, d: fmt(mean(variants[n], b, m) / 2, d),
        "per": lambda n, b, m1, m2, d: fmt(mean(variants[n], b, m1) / mean(variants[n], b, m2), d),
        "paired": lambda n, a, b, d: pm(paired(variants[n], a, b), int(d)),
        "gap": lambda n, a, b: f"{gap(variants[n], a, b):+.1f} %".replace("-", "−"),
        "run": lambda key, d: fmt(run[key], d),
        "selection": lambda t: selection(t, variants),
        "stress": lambda t: stress(t),
        "vmas": lambda t: vmas(t),
        "rl": lambda t: rl(t, variants),
        "noisy": lambda t, clean: noisy(t, clean),
        "seeds": lambda: seeds_section(by_task),
        "seeds_glance": lambda: seeds_glance(by_task).rstrip("\n"),
        "seeds_planned": lambda: ", ".join(map(str, PLANNED_SEEDS)),
        "seedmean": lambda t, seed, b, m, d: fmt(seed_mean(by_task, t, int(seed), b, m), d),
    }

    def sub(m: re.Match) -> str:
        op, *args = m.group(1).split()
        if op not in ops:
            raise SystemExit(f"{TEMPLATE}: unknown placeholder {{{{{m.group(1)}}}}}")
        try:
            return ops[op](*args)
        except (KeyError, TypeError, ValueError) as e:
            raise SystemExit(f"{TEMPLATE}: placeholder {{{{{m.group(1)}}}}}: {type(e).__name__} {e}") from None

    return re.sub(r"\{\{([^{}]+)\}\}", sub, template)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--collect", action="store_true", help="first write docs/results/ from the artifacts")
    ap.add_argument("--root", default=str(ROOT / "outputs"), help="runs root of the paper protocol's artifacts")
    ap.add_argument("--check", action="store_true", help="exit 1 if docs/results.md differs from the render")
    ap.add_argument("--figures", action="store_true", help="also redraw docs/figures/<task>.png from docs/results/")
    ap.add_argument("--collect-stress", default="", metavar="EXP",
                    help="first write docs/results/stress-<task>.json from a run directory where `neurosym stress` ran")
    ap.add_argument("--collect-select", default="", metavar="EXP",
                    help="first write docs/results/select-<task>.json from a run directory where `neurosym select` ran")
    ap.add_argument("--collect-rl", default="", metavar="EXP",
                    help="first write docs/results/rl-<task>.json from a run directory where `neurosym rl` ran")
    ap.add_argument("--collect-noisy", default="", metavar="EXP",
                    help="first write docs/results/<task>.json from a link-failure run directory (appendix E)")
    ap.add_argument("--collect-vmas", default="", metavar="EXP",
                    help="first write docs/results/vmas-<scenario>.json from a VMAS run directory (docs/vmas.md)")
    ap.add_argument("--wall", type=float, default=None, metavar="S",
                    help="with --collect-vmas: the measured wall seconds of the pipeline")
    ap.add_argument("--seeds", default=str(SEEDS), metavar="DIR",
                    help="the seed files to render the training-seed sections from (default docs/results/seeds)")
    ap.add_argument("--out", default="", metavar="FILE",
                    help="write the page here instead of docs/results.md (a preview; --check still reads the page)")
    ap.add_argument("--seed-figures", default="", metavar="DIR",
                    help="draw the training-seed figures from --seeds into DIR (with --figures: docs/figures)")
    a = ap.parse_args()
    if a.collect:
        collect(Path(a.root))
    if a.collect_select:
        collect_select(Path(a.collect_select))
    if a.collect_stress:
        collect_stress(Path(a.collect_stress))
    if a.collect_rl:
        collect_rl(Path(a.collect_rl))
    if a.collect_noisy:
        collect_noisy(Path(a.collect_noisy))
    if a.collect_vmas:
        collect_vmas(Path(a.collect_vmas), a.wall)
    if a.collect_vmas or a.figures:
        draw_vmas()
    if a.collect or a.figures or a.collect_select or a.collect_stress or a.collect_rl:
        draw_figures()
        for task in VARIANTS:
            draw_pareto(task)
            draw_stress(task)
    by_task = load_seeds(Path(a.seeds))
    if a.seed_figures or a.figures:
        draw_seed_figures(by_task, Path(a.seed_figures) if a.seed_figures else DOCS / "figures")
    text = render(TEMPLATE.read_text(), *load(), by_task)
    target = Path(a.out) if a.out and not a.check else DOCS / "results.md"
    if a.check:
        if target.read_text() != text:
            print("docs/results.md is not what docs/results.template.md and docs/results/ give; "
                  "run python benchmarks/results_doc.py", file=sys.stderr)
            raise SystemExit(1)
        print("docs/results.md matches its template and result files")
        return
    target.write_text(text)
    print(f"wrote {target}")


if __name__ == "__main__":
    main()
