"""Does prog-retrained beat no-comm because it communicates? The control against silence (issue 37).

The pipeline's no-comm is trained from scratch, while prog-retrained starts from the oracle's weights and is
retrained under the program. The control retrains the same oracle as long under a program that never fires
(silence) and evaluates it on the same test seeds, so the program's gain over silence is paired and is what its
communication buys; the gain of silence over no-comm is what retraining the oracle's weights buys.

    python benchmarks/silence_control.py --tasks consensus vmas-navigation-avoid --seeds 0 1 2
    python benchmarks/silence_control.py --tasks swarm-200 --seeds 1     # also the pick and b6 at 600 rollouts
    python benchmarks/silence_control.py --collect                        # only collects what has run

A task-seed's control needs its pipeline run (benchmarks/beyond_paper.py) under outputs/beyond; the retrainings
run under outputs/controls/<task>-seed<S>/r<rollouts> from a copy of its oracle (a retrained model's name does not
say its length). Result files: docs/results/beyond/controls/<task>-seed<S>.json, rendered on the results page.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.beyond_paper import OUT, SEEDS, TASKS, exp_dir, run_args  # noqa: E402
from benchmarks.run_seeds import PIN, neurosym, write_result  # noqa: E402

from neurosym_cli.stats import mean_ci  # noqa: E402
from neurosym_cli.utils.io import write_text  # noqa: E402

RUNS = ROOT / "outputs" / "beyond"
"""the pipeline runs (benchmarks/beyond_paper.py's runs root)"""
CONTROLS = ROOT / "outputs" / "controls"
SILENT = "random(filter(d <= -1.0, l))\n"
"""a program that never fires (d >= 0)"""
MORE = {("swarm-200", 1): {"rollouts": (600,), "candidates": ("b6",)}}
"""task-seeds measured further: also retrained for these lengths, also these front candidates (by name)"""


def plan(name: str, seed: int) -> tuple[dict[str, str], tuple[int, ...]]:
    """(program name -> its text, retraining lengths) of one task-seed's control: silence and the front's pick
    (and MORE's), at the pipeline's retraining length (and MORE's)."""
    res = json.loads((OUT / f"{name}-seed{seed}.json").read_text())
    pick = res["front_pick"]
    by_name = {c["name"]: c["program"] for c in pick["candidates"]}
    more = MORE.get((name, seed), {})
    programs = {"silent": SILENT, pick["picked"]["name"]: pick["picked"]["program"],
                **{c: by_name[c] for c in more.get("candidates", ())}}
    return programs, (int(pick["retrain_rollouts"]), *more.get("rollouts", ()))


def root(name: str, seed: int, rollouts: int) -> Path:
    return CONTROLS / f"{name}-seed{seed}" / f"r{rollouts}"


def program_file(name: str, seed: int, program: str, text: str) -> Path:
    path = CONTROLS / f"{name}-seed{seed}" / "programs" / f"{program}.txt"
    if not path.exists():
        write_text(path, text)  # atomically: a run killed here leaves no half program
    return path


def evaluation(exp: Path, program: str) -> Path | None:
    """The metrics.json of prog-retrained under the program file named ``program`` in run directory ``exp``."""
    found = sorted((exp / "eval").glob(f"prog-retrained-file-{program}-*/metrics.json"))
    return found[0] if found else None


def control_exp(name: str, seed: int, rollouts: int) -> Path:
    """The control's run directory: the pipeline's, moved under its own runs root."""
    pipeline = exp_dir(TASKS[name], seed, RUNS)
    return root(name, seed, rollouts) / pipeline.relative_to(RUNS)


def run_missing(name: str, seed: int) -> None:
    """Retrain and evaluate each program of the plan at each length, where not evaluated yet."""
    programs, lengths = plan(name, seed)
    pipeline = exp_dir(TASKS[name], seed, RUNS)
    env = {**os.environ, **PIN}
    for rollouts in lengths:
        exp = control_exp(name, seed, rollouts)
        if not (exp / "train/oracle").exists():
            shutil.copytree(pipeline / "train/oracle", exp / "train/oracle")
        for program, text in programs.items():
            if evaluation(exp, program):
                continue
            args = [*run_args(TASKS[name], seed, root(name, seed, rollouts), (), None),
                    f"budget.retrain_rollouts={rollouts}", f"program={program_file(name, seed, program, text)}"]
            config_dir = args.index("--config-dir") if "--config-dir" in args else None
            if config_dir is not None:  # relative to the repository root, where the commands run
                args[config_dir + 1] = str(ROOT / args[config_dir + 1])
            for verb in (["retrain"], ["eval", "baseline=prog-retrained"]):
                subprocess.run([neurosym(), *verb, *args], env=env, cwd=ROOT, check=True)


def collect(name: str, seed: int) -> dict | None:
    """Per (program, length): loss (mean and 95 % t half-width over the test seeds), max in+out, the share of the
    pipeline's gap (no-comm - tf-full) closed, and the paired difference to silence retrained as long."""
    res = json.loads((OUT / f"{name}-seed{seed}.json").read_text())
    base = {b: res["baselines"][b]["summary"]["cost"]["mean"] for b in ("tf-full", "no-comm")}
    programs, lengths = plan(name, seed)
    rows, per = [], {}
    for rollouts in lengths:
        for program, text in programs.items():
            m = evaluation(control_exp(name, seed, rollouts), program)
            if m is None:
                continue
            d = json.loads(m.read_text())
            per[rollouts, program] = {r["seed"]: r["cost"] for r in d["per_seed"]}
            cost = d["summary"]["cost"]["mean"]
            rows.append({"program": program, "retrain_rollouts": rollouts,
                         "cost": mean_ci(list(per[rollouts, program].values())),
                         "max_in_out": d["summary"]["max_degree"]["mean"],
                         "gap_closed": (base["no-comm"] - cost) / (base["no-comm"] - base["tf-full"]),
                         "text": text.strip()})
    if not rows:
        return None
    for r in rows:
        s, mine = per.get((r["retrain_rollouts"], "silent")), per[r["retrain_rollouts"], r["program"]]
        r["minus_silent"] = mean_ci([mine[k] - s[k] for k in sorted(set(s) & set(mine))]) if s else None
    return {"task": name, "seed": seed, "tf_full": base["tf-full"], "no_comm": base["no-comm"], "rows": rows,
            "about": __doc__.split("\n\n")[1].replace("\n", " ")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tasks", nargs="+", default=list(TASKS), choices=list(TASKS))
    ap.add_argument("--seeds", nargs="+", type=int, default=list(SEEDS))
    ap.add_argument("--collect", action="store_true", help="only collect what has run")
    a = ap.parse_args()
    for name in a.tasks:
        for seed in a.seeds:
            if not (OUT / f"{name}-seed{seed}.json").exists():
                continue  # its pipeline has not finished
            if not a.collect:
                run_missing(name, seed)
            out = collect(name, seed)
            if out:
                write_result(OUT / "controls" / f"{name}-seed{seed}.json", out)
                for r in out["rows"]:
                    print(f"{name} seed {seed} {r['program']:7s} {r['retrain_rollouts']} rollouts: {r['cost'][0]:.3f}"
                          f" ± {r['cost'][1]:.3f}, gap closed {r['gap_closed']:.0%}, max in+out {r['max_in_out']:.2f}")


if __name__ == "__main__":
    main()
