"""{{paper_defaults}}: the paper's claims under today's defaults beside the paper's method, per task over training
seeds (docs/results/seeds-defaults/, `python benchmarks/beyond_paper.py --suite paper`; docs/results/seeds/,
benchmarks/run_seeds.py): issue 37's "the paper's tasks lose no claim"."""

from __future__ import annotations

import json
from pathlib import Path

from benchmarks.beyond_paper import PAPER_TASKS, SUITES
from neurosym_cli.stages.front_select import about
from neurosym_cli.verb_config import PipelineConfig

from .files import PLANNED_SEEDS, SEED_TASKS, load_seeds, seed_variant
from .seed_sections import claim_over_seeds, seed_claims
from .tables import shown

DEFAULTS = SUITES["paper"].out
MARGIN_FILE = DEFAULTS.parent / "front-margin.json"
"""benchmarks/front_margin.py's rows: each paper task-seed's front pick re-made at other pipeline.margin values"""
MARGIN_BEYOND = DEFAULTS.parent / "front-margin-beyond.json"
"""the same for the tasks beyond the paper (``--suite beyond``: issue 37's four tests)"""
DEFAULT_MARGIN = PipelineConfig().margin


def trade(runs: list, baseline: str, metric: str) -> float:
    """``baseline``'s ``metric`` (a test-seed mean) averaged over the training seeds ``runs``."""
    return sum(seed_variant(r)["baselines"][baseline]["summary"][metric]["mean"] for r in runs) / len(runs)


def lost_on(task: str, runs: list, per_default: dict, per_method: dict, digits: int) -> list[str]:
    """One line per training seed on which a claim holds under the paper's method and not under the defaults: the
    claims, prog-retrained's and tf-full's test loss, and how the front's pick stood on validation against the
    validation-best candidate (the pick may cost up to pipeline.margin of loss for a lower degree)."""
    lines = []
    for r in runs:
        mine, theirs = per_default.get(r.seed), per_method.get(r.seed)
        if isinstance(mine, str) or isinstance(theirs, str) or not mine or not theirs:
            continue
        held = {c.name for c in theirs if c.holds}
        gone = [c for c in mine if not c.holds and c.name in held]
        if not gone:
            continue
        res = json.loads(Path(r.source).read_text())
        base = seed_variant(r)["baselines"]
        loss = {b: base[b]["summary"]["cost"]["mean"] for b in ("prog-retrained", "tf-full", "det-prog-retrained")
                if b in base}
        line = f"- seed {r.seed}: {'; '.join(c.long for c in gone)}."
        if any("det-prog-retrained" in c.name for c in gone) and "det-prog-retrained" in loss:
            line += f" det-prog-retrained's test loss {loss['det-prog-retrained']:.{digits}f}."
        if "prog-retrained" in loss and "tf-full" in loss:
            line += (f" prog-retrained {loss['prog-retrained']:.{digits}f} against tf-full {loss['tf-full']:.{digits}f}"
                     f" ({100 * (loss['prog-retrained'] / loss['tf-full'] - 1):+.1f} %)"
                     + (f" and dist {base['dist']['summary']['cost']['mean']:.{digits}f}" if "dist" in base else "")
                     + " on the test seeds.")
        front = res.get("front_pick") or {}
        cands = front.get("candidates") or []
        picked = next((c for c in cands if c.get("picked")), None)
        best = min((c for c in cands if not c.get("excluded") and c.get("loss_mean") is not None),
                   key=lambda c: c["loss_mean"], default=None)
        if picked and best and picked is not best:
            line += (f" On validation the pick ({picked['name']}, max in+out {picked['degree']:.2f}) was "
                     f"{picked['loss_mean']:.{digits}f}, {picked['diff']:+.{digits}f} ± {picked['diff_ci']:.{digits}f}"
                     f" (paired 95 % t) above the best candidate ({best['name']}, {best['loss_mean']:.{digits}f}, "
                     f"max in+out {best['degree']:.2f}): within pipeline.margin = {front.get('margin')} of its loss.")
        lines.append(line)
    return lines


def margin_table(method: dict, path: Path = MARGIN_FILE) -> list[str]:
    """The front selection's margin against the claims: per margin, per task, the claims the defaults would lose
    (held on fewer seeds than under the paper's method, on the same seeds) and prog-retrained's mean test max
    in+out, with every other baseline as run. [] without the file."""
    if not path.exists():
        return []
    rows = json.loads(path.read_text())
    tasks = sorted({r["task"] for r in rows})
    margins = list(dict.fromkeys(r["margin"] for r in rows))
    out = ["The margin of the pick, measured (`python benchmarks/front_margin.py --json "
           "docs/results/front-margin.json`): every candidate of the front was retrained and validated by the runs "
           "above, so the rule can be re-applied at another `pipeline.margin` to the validation rows each run "
           "recorded and its pick evaluated on the test seeds, nothing retrained. Cells: the claims lost (held on "
           "fewer of the seeds than under the paper's method), then prog-retrained's test max in+out averaged over "
           "the seeds.", "", "| pipeline.margin | " + " | ".join(tasks) + " |", "|---|" + "---|" * len(tasks)]
    for m in margins:
        cells = []
        for task in tasks:
            mine = [r for r in rows if r["task"] == task and r["margin"] == m]
            seeds = {r["seed"] for r in mine}
            _, per_method = seed_claims(task, [r for r in method.get(task, []) if r.seed in seeds])
            theirs = [cl for cl in per_method.values() if not isinstance(cl, str)]
            lost = [name for name in mine[0]["holds"]
                    if sum(r["holds"][name] for r in mine) / len(mine)
                    < sum(next(c.holds for c in cl if c.name == name) for cl in theirs) / max(len(theirs), 1)]
            deg = sum(r["test_max_degree"] for r in mine) / len(mine)
            cells.append(f"{'; '.join(lost) or 'none'} ({deg:.2f})")
        label = "null (the paper's test)" if m is None else f"{m:g}" + (" (default)" if m == DEFAULT_MARGIN else "")
        out.append(f"| {label} | " + " | ".join(cells) + " |")
    if MARGIN_BEYOND.exists():  # the tasks beyond the paper: does any of the four tests move with the margin?
        rows = json.loads(MARGIN_BEYOND.read_text())
        first = {(r["task"], r["seed"]): r["holds"] for r in rows if r["margin"] == rows[0]["margin"]}
        moved = sorted({f"{r['task']} seed {r['seed']}" for r in rows if r["holds"] != first[(r["task"], r["seed"])]})
        out += ["", f"On the tasks beyond the paper ({', '.join(sorted({r['task'] for r in rows}))}; "
                "`python benchmarks/front_margin.py --suite beyond --json docs/results/front-margin-beyond.json`), "
                + (f"issue 37's four tests change with the margin on {', '.join(moved)}." if moved else
                   "none of issue 37's four tests changes on any training seed at any of these margins.")]
    return out


def _rules(program: str, task: str, run) -> str:
    """A picked program's rules as shown simplified, on one line (``round k:`` before each round's when several)."""
    text, _, _ = shown(program, task, (run.pick or {}).get("features", "v1"))
    rounds: list[list[str]] = [[]]  # rules per round, the round headers dropped ("round 2:" starts a new one)
    for line in (ln.strip() for ln in text.splitlines() if ln.strip() and not ln.startswith("#")):
        if not line.startswith("round "):
            rounds[-1].append(line)
        elif rounds[-1]:
            rounds.append([])
    return "; ".join(rounds[0]) if len(rounds) == 1 else " ".join(
        f"round {k}: {'; '.join(rules)}." for k, rules in enumerate(rounds, start=1))


def _matched(choice: dict) -> str:
    """How a choice was read against another family's validation-best (front_select.Family.matches), in words: ""
    where it was not (prog's own choices, runs before it, or its own best the lower)."""
    ref = choice.get("reference")
    own = [c for c in choice.get("candidates", []) if not c.get("excluded")]
    if not ref or not own or ref["loss_mean"] >= min(c["loss_mean"] for c in own):
        return ""
    picked = next(c for c in own if c.get("picked"))
    return (f" (read at {ref['family']}'s validation-best, {ref['name']} at {ref['loss_mean']:.4g}: "
            + ("the lowest degree within the margin of it)" if picked.get("similar") else
               f"none within the margin of it, its lowest validation loss, {picked['loss_mean']:.4g})"))


def paper_defaults(directory: Path = DEFAULTS) -> str:
    """Per paper task: the training seeds each method ran, the picks under the defaults, and one row per claim:
    on how many seeds it holds under the paper's method (its model selection) and under the defaults, with the
    claim's quantity across seeds; a claim the defaults hold on fewer seeds than the paper's method is marked."""
    method, defaults = load_seeds(), load_seeds(directory)
    out = []
    for task in SEED_TASKS:
        runs = defaults.get(task, [])
        out += [f"### {task}", ""]
        if not runs:
            out += [f"Not yet run under the defaults (training seeds {', '.join(map(str, PLANNED_SEEDS))} planned; "
                    f"`python benchmarks/beyond_paper.py --suite paper` resumes across sessions).", ""]
            continue
        picks = []
        for r in runs:
            res = json.loads(Path(r.source).read_text())
            for key, who in (("front_pick", ""), ("det_front_pick", "det-prog, ")):  # prog's, then det-prog's
                pick = (res.get(key) or {}).get("picked") or {}
                if pick:
                    picks.append(f"- seed {r.seed}, {who}{about(pick)}{_matched(res.get(key))}: "
                                 f"`{_rules(pick['program'], task, r)}`")
        names, per_default = seed_claims(task, runs)
        _, per_method = seed_claims(task, method.get(task, []))
        digits = 3 if task == "unlabeled-goals" else 2
        seeds = [r.seed for r in runs]
        out += [f"Training seed{'s' if len(seeds) > 1 else ''} {', '.join(map(str, seeds))} under the defaults: "
                f"`{PAPER_TASKS[task].args[0]} {PAPER_TASKS[task].args[1]} seed=S` with every baseline "
                "(`neurosym pipeline`, one thread, pinned kernels). The paper's method: its training seeds of the "
                "section above (`neurosym select`'s pick, MCMC, the single-λ program). Cells: seeds the claim holds "
                "on / seeds checked; the claim's quantity, mean ± 95 % t half-width across those seeds.", "",
                "| claim | paper's method | defaults | lost? |", "|---|---|---|---|"]
        any_lost = False
        for name in names:
            m = claim_over_seeds(name, {s: v for s, v in per_method.items() if s in seeds}, digits)
            d = claim_over_seeds(name, per_default, digits)
            lost = ("n/a" if not (d["n"] and m["n"]) else "**yes**" if d["k"] / d["n"] < m["k"] / m["n"] else "no")
            any_lost = any_lost or lost == "**yes**"
            out.append(f"| {d['short']} | {m['k']}/{m['n']}; {m['across']} | {d['k']}/{d['n']}; {d['across']} | "
                       f"{lost} |")
        if any_lost and set(seeds) & {r.seed for r in method.get(task, [])}:  # what the programs traded
            common = sorted(set(seeds) & {r.seed for r in method.get(task, [])})  # the seeds both ran
            both = [(label, [r for r in rs if r.seed in common]) for label, rs in
                    (("the defaults", runs), ("the paper's method", method.get(task, [])))]
            cells = [f"{b} under {label}: loss {trade(rs, b, 'cost'):.{digits}f}, max in+out "
                     f"{trade(rs, b, 'max_degree'):.2f}, max out {trade(rs, b, 'max_out'):.2f}"
                     for b in ("prog-retrained", "det-prog-retrained") for label, rs in both if rs]
            out += ["", "Where a claim is lost, what the programs traded (test means, averaged over the training "
                    f"seeds both ran, {', '.join(map(str, common))}): " + "; ".join(cells) + ". Under the defaults "
                    "prog-retrained runs the lowest degree of the front whose validation loss is within "
                    "pipeline.margin of the best candidate's, det-prog-retrained the same among its own front (argmax "
                    "rules only), where the run made one, with prog's validation-best as the best where it is lower "
                    "(the ablation at the method's loss, docs/fidelity.md; said with each pick below)."]
            out += ["", "Per seed, where the defaults lose a claim the paper's method holds there:", "",
                    *lost_on(task, runs, per_default, per_method, digits)]
        out += ["", "The programs the defaults picked (the front's candidate, then its rules, shown simplified):", "",
                *picks, ""]
    out += margin_table(method)
    return "\n".join(out).rstrip("\n")
