"""Is the swarm's prog-retrained better than no-comm because it communicates? A control (issue 37).

The pipeline's no-comm is trained from scratch; prog-retrained starts from the oracle's weights and is retrained
under the program. On swarm-200 the front's programs hear almost nobody (max in+out 0.4-8 of tf-full's 398), so
the control is the oracle retrained the same way under a program that never fires (silence). Both are retrained
for the budget's 200 rollouts and for 600, from the same oracle (training seed 1), and evaluated on the same 20
test seeds (paired differences). The programs: silence and two of the front's candidates of that seed (b1, the
pick; b6, the most communicating), copied from its run directory.

    python benchmarks/swarm_control.py            # runs what is missing (resumes), then writes the result file
    python benchmarks/swarm_control.py --collect  # only collects

Result file: docs/results/beyond/controls/swarm-200-seed1.json, rendered on the results page under swarm-200.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.run_seeds import PIN, neurosym, write_result  # noqa: E402

from neurosym_cli.stats import mean_ci  # noqa: E402

SEED = 1
PIPELINE = ROOT / "outputs/beyond/swarm/swarm/seed1"
"""the pipeline run of swarm-200 training seed 1 (benchmarks/beyond_paper.py): its oracle and front"""
RESULT = ROOT / "docs/results/beyond/swarm-200-seed1.json"
OUT = ROOT / "docs/results/beyond/controls/swarm-200-seed1.json"
ROOTS = {200: ROOT / "outputs/swarm-short", 600: ROOT / "outputs/swarm-longer"}
"""retraining rollouts -> runs root (a copy of the pipeline's oracle in each: the retrained model's name does not
say its length)"""
PROGRAMS = {"silent": "random(filter(d <= -1.0, l))\n",  # d >= 0: never fires
            "b1": PIPELINE / "select/front/k2-lam0.25-v1-scaled-hybrid-b1.txt",
            "b6": PIPELINE / "select/front/k2-lam0.25-v1-scaled-hybrid-b6.txt"}
ARGS = ("task=swarm", "task.agents_per_group=100", "budget=swarm", f"seed={SEED}", "threads=1", "progress=plain",
        "plots=false")


def program_file(name: str) -> Path:
    """The program's file under the 600-rollout root's programs/ (written once from PROGRAMS)."""
    path = ROOTS[600] / "programs" / f"{name}.txt"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        src = PROGRAMS[name]
        path.write_text(src.read_text() if isinstance(src, Path) else src)
    return path


def metrics(rollouts: int, name: str) -> Path | None:
    """The evaluation of ``name`` retrained for ``rollouts``, if it exists."""
    evals = ROOTS[rollouts] / f"swarm/swarm/seed{SEED}/eval"
    found = sorted(evals.glob(f"prog-retrained-file-{name}-*/metrics.json"))
    return found[0] if found else None


def run_missing() -> None:
    """Retrain and evaluate every (program, rollouts) without an evaluation, from a copy of the pipeline's oracle."""
    import os

    env = {**os.environ, **PIN}
    for rollouts, root in ROOTS.items():
        oracle = root / f"swarm/swarm/seed{SEED}/train/oracle"
        if not oracle.exists():
            shutil.copytree(PIPELINE / "train/oracle", oracle)
        for name in PROGRAMS:
            if metrics(rollouts, name):
                continue
            args = [*ARGS, f"runs_root={root}", f"budget.retrain_rollouts={rollouts}", f"program={program_file(name)}"]
            for verb in (["retrain"], ["eval", "baseline=prog-retrained"]):
                subprocess.run([neurosym(), *verb, *args], env=env, cwd=ROOT, check=True)


def collect() -> dict:
    """Per (program, rollouts): mean cost and 95 % t half-width over the test seeds, max in+out, the share of the
    pipeline's gap (no-comm - tf-full) closed, and the paired difference to silence retrained as long."""
    res = json.loads(RESULT.read_text())
    base = {b: res["baselines"][b]["summary"]["cost"]["mean"] for b in ("tf-full", "no-comm")}
    rows, per = [], {}
    for rollouts in ROOTS:
        for name in PROGRAMS:
            m = metrics(rollouts, name)
            if m is None:
                continue
            d = json.loads(m.read_text())
            per[rollouts, name] = {r["seed"]: r["cost"] for r in d["per_seed"]}
            cost = d["summary"]["cost"]["mean"]
            rows.append({"program": name, "retrain_rollouts": rollouts,
                         "cost": mean_ci(list(per[rollouts, name].values())),
                         "max_in_out": d["summary"]["max_degree"]["mean"],
                         "gap_closed": (base["no-comm"] - cost) / (base["no-comm"] - base["tf-full"]),
                         "text": program_file(name).read_text().strip()})
    for r in rows:
        s, mine = per.get((r["retrain_rollouts"], "silent")), per[r["retrain_rollouts"], r["program"]]
        r["minus_silent"] = mean_ci([mine[k] - s[k] for k in sorted(set(s) & set(mine))]) if s else None
    return {"task": "swarm-200", "seed": SEED, "tf_full": base["tf-full"], "no_comm": base["no-comm"], "rows": rows,
            "about": __doc__.split("\n\n")[1].replace("\n", " ")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--collect", action="store_true", help="only collect what has been run")
    a = ap.parse_args()
    if not a.collect:
        run_missing()
    out = collect()
    write_result(OUT, out)
    for r in out["rows"]:
        print(f"{r['program']:7s} {r['retrain_rollouts']} rollouts: {r['cost'][0]:.1f} ± {r['cost'][1]:.1f}, "
              f"gap closed {r['gap_closed']:.0%}, max in+out {r['max_in_out']:.2f}")


if __name__ == "__main__":
    main()
