"""{{beyond}}: the tasks beyond the paper with the defaults only (issue 37), from docs/results/beyond/*.json
(benchmarks/beyond_paper.py writes them and holds the verdict's arithmetic)."""

from __future__ import annotations

import json
import math

from benchmarks.beyond_paper import BASELINES, OUT, SEEDS, TASKS, front_reach, verdicts

from neurosym_cli.stages.front_select import about

from .tables import minus

CONTROL_SCRIPT = "silence_control.py"
"""the script that runs and collects the controls (benchmarks/)"""


def _pm(x: tuple[float, float], digits: int = 3) -> str:
    return minus(f"{x[0]:+.{digits}f} ± {x[1]:.{digits}f}")


def _why_not_half(v: dict) -> list[str]:
    """Lines that say, from the front's validation, why seeds miss the half-gap bar: whether any candidate of the
    front reached it (then the choice is what fell short) or none did (then the programs did)."""
    lines = []
    for seed, r in v["seeds"].items():
        reach = front_reach(v["results"][seed])
        if r["holds"]["closes half the gap"] or reach is None:
            continue
        lo, hi = reach["loss_range"]
        if reach["best_share"] < 0.5:
            verdict = "no candidate reached half, so the choice is not what fell short"
        elif reach["best"] == reach["picked"]:
            verdict = (f"the pick itself, at half on validation and {r['gap_closed']:.0%} on the test seeds: the bar "
                       "is at the edge of what the programs reach")
        else:
            verdict = (f"half was within reach on validation, and the pick ({reach['picked']}), the lowest degree "
                       "statistically similar to the best, fell below it")
        lines.append(f"- seed {seed}: the {reach['candidates']} front candidates, each retrained for "
                     f"{reach['retrain_rollouts']} rollouts, validated at {lo:.1f}-{hi:.1f} "
                     f"(tf-full {reach['tf_full']:.1f}, no-comm {reach['no_comm']:.1f}, half the gap "
                     f"{reach['half']:.1f}); the best, {reach['best']} "
                     f"(max in+out {reach['best_degree']:.2f}), closes {reach['best_share']:.0%} there: {verdict}")
    if lines:
        lines = ["", "Why the half-gap bar is missed, from the front's validation (stages/front_select.py):", "",
                 *lines]
    return lines


def _digits(scale: float) -> int:
    """Decimals that give a loss of this size four significant digits (700.2, 2.378)."""
    return max(1, 3 - math.floor(math.log10(abs(scale)))) if scale else 3


def _control(name: str) -> list[str]:
    """The controls of docs/results/beyond/controls/<task>-seed<S>.json (benchmarks/silence_control.py), if run: the
    oracle retrained under silence against retrained under the front's programs, as long and from the same oracle."""
    files = sorted((OUT / "controls").glob(f"{name}-seed*.json"))
    if not files:
        return []
    out = ["", f"Control against silence (`python benchmarks/{CONTROL_SCRIPT} --tasks {name}`): "
           + json.loads(files[0].read_text())["about"] + " Loss: mean ± 95 % t half-width over the test seeds; "
           "− silence: the program's loss minus silence's retrained as long, paired over the test seeds (negative: "
           "the program is better)."]
    for path in files:
        c = json.loads(path.read_text())
        k = _digits(c["tf_full"])
        out += ["", f"Training seed {c['seed']} (docs/results/beyond/controls/{path.name}; the pipeline's tf-full "
                f"{c['tf_full']:.{k}f}, no-comm {c['no_comm']:.{k}f}):", "",
                "| program | retrained for | loss | max in+out | gap closed | − silence (paired) |",
                "|---|---|---|---|---|---|"]
        for r in sorted(c["rows"], key=lambda r: (r["retrain_rollouts"], r["program"] != "silent", r["program"])):
            vs = _pm(r["minus_silent"], k) if r["minus_silent"] and r["program"] != "silent" else ""
            out.append(f"| {r['program']} | {r['retrain_rollouts']} rollouts | {_pm(r['cost'], k).lstrip('+')} | "
                       f"{r['max_in_out']:.2f} | {r['gap_closed']:.0%} | {vs} |")
        texts = {r["program"]: "; ".join(ln for ln in r["text"].splitlines() if ln.strip() and not ln.startswith("#"))
                 for r in c["rows"]}
        out += ["", "The programs: " + "; ".join(f"{n}: `{t}`" for n, t in sorted(texts.items())) + "."]
        judged = [r for r in c["rows"] if r["program"] != "silent" and r["minus_silent"]]
        better = [r for r in judged if r["minus_silent"][0] + r["minus_silent"][1] < 0]
        gap = c["no_comm"] - c["tf_full"]
        silent = {r["retrain_rollouts"]: r["gap_closed"] for r in c["rows"] if r["program"] == "silent"}
        if judged and silent:
            best = min(judged, key=lambda r: r["minus_silent"][0])
            gain = -best["minus_silent"][0] / gap  # the programs' best gain over silence, as a share of the gap
            out += ["", f"{len(better)} of the {len(judged)} program-and-length pairs beat silence retrained as long. "
                    "Silence retrained from the oracle closes " + " and ".join(
                        f"{v:.0%} ({n} rollouts)" for n, v in sorted(silent.items())) + " of the gap itself"
                    + f"; the programs' best gain over it, {best['program']} at {best['retrain_rollouts']} rollouts, "
                    f"is {gain:.1%} of the gap"
                    + (": what the pipeline's prog-retrained gains over its no-comm here comes almost all from "
                       "retraining the oracle's weights, not from what the programs let agents hear."
                       if gain < 0.1 * min(silent.values()) else ".")]
    return out


def beyond() -> str:
    """One table per task: per training seed each baseline's loss and max in+out, the paired differences, the share
    of the gap closed and of tf-full's degree, and the four tests; then the tasks not yet run."""
    found = verdicts(OUT)
    out = []
    for name, v in found.items():
        task = TASKS[name]
        first = next(iter(v["seeds"].values()))
        out += [f"### {name}", "", f"{task.about}. Command: `neurosym pipeline {' '.join(task.args)} seed=S "
                f"\"baselines=[{','.join(BASELINES)}]\"` (defaults otherwise).", "",
                "| training seed | tf-full | prog-retrained | no-comm | max in+out (prog-retrained / tf-full) | "
                "no-comm − tf-full | no-comm − prog-retrained | gap closed | share of tf-full's degree |",
                "|---|---|---|---|---|---|---|---|---|"]
        for seed, r in v["seeds"].items():
            c, d = r["cost"], r["max_in_out"]
            out.append(f"| {seed} | {c['tf-full']:.3f} | {c['prog-retrained']:.3f} | {c['no-comm']:.3f} | "
                       f"{d['prog-retrained']:.2f} / {d['tf-full']:.2f} | {_pm(r['comm_helps'])} | "
                       f"{_pm(r['prog_better_than_no_comm'])} | {r['gap_closed']:.0%} | {r['degree_share']:.2f} |")
        out += ["", "The programs picked (the front's candidate, then the program's rules):", ""]
        for seed, res in v["results"].items():
            pick = (res.get("front_pick") or {}).get("picked") or {}
            if pick:
                rules = "; ".join(line for line in pick["program"].splitlines() if line.strip())
                out.append(f"- seed {seed}, {about(pick)}: `{rules}`")
        out += _why_not_half(v)
        g, s = v["across"]["gap_closed"], v["across"]["degree_share"]
        n = len(v["seeds"])
        across = (f"across the {n} training seeds (mean ± 95 % t half-width over training seeds): gap closed "
                  f"{g[0]:.0%} ± {g[1]:.0%}, share of tf-full's degree {s[0]:.2f} ± {s[1]:.2f}" if n > 1 else
                  "one training seed so far: no interval across seeds")
        tests = {k: sum(r["holds"][k] for r in v["seeds"].values()) for k in first["holds"]}
        todo = [s for s in SEEDS if s not in v["seeds"]]
        if todo:  # a task under way: the bar is over seeds 0, 1, 2
            across += (f"; training seed{'s' if len(todo) > 1 else ''} {', '.join(map(str, todo))} not yet run "
                       "(benchmarks/beyond_paper.py resumes it)")
        out += ["", f"Losses: mean over the evaluation seeds; differences: paired mean ± 95 % t half-width over the "
                f"evaluation seeds; {across}. Holds on "
                + ", ".join(f"{k}: {m} of {n} seeds" for k, m in tests.items()) + ".", ""]
        control = _control(name)
        out += [*control[1:], ""] if control else []
    missing = [n for n in TASKS if n not in found]
    if missing:
        out += ["Not yet run (benchmarks/beyond_paper.py resumes them across sessions): "
                + "; ".join(f"{n} ({TASKS[n].about})" for n in missing) + ".", ""]
    return "\n".join(out).rstrip("\n")
