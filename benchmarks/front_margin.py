"""How the paper's claims under the defaults move with the front selection's margin (issue 37; `pipeline.margin`).

    python benchmarks/front_margin.py                  # every committed paper task-seed under the defaults
    python benchmarks/front_margin.py --suite beyond   # the tasks beyond the paper (issue 37's four tests)
    python benchmarks/front_margin.py --json docs/results/front-margin.json

The defaults pick, among the front's programs retrained and validated, the lowest max in+out whose validation loss
is within ``pipeline.margin`` (0.01) of the validation-best's (stages/front_select.py). Every candidate of a run
was retrained and validated already, so another margin's pick costs only its test evaluation: for each result file
of docs/results/seeds-defaults/ (its run directory under outputs/beyond must still be there) this re-applies the
rule (``front_select.pick``) at each margin to the validation rows the run recorded, evaluates each pick not yet
evaluated on the test seeds (`neurosym eval ... baseline=prog-retrained program=<candidate>`, a few seconds), and
checks the paper's claims (benchmarks/results/claims.toml; with ``--suite beyond``, issue 37's four tests of
benchmarks/beyond_paper.py) with that pick as prog-retrained, every other baseline as the run made it. Nothing is retrained; the test seeds serve only to report, never to choose.
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from benchmarks.beyond_paper import SUITES, verdict  # noqa: E402
from benchmarks.results.claims import claims  # noqa: E402
from benchmarks.results.files import METRICS, load_seeds, seed_variant  # noqa: E402
from neurosym_cli.stages.front_select import pick  # noqa: E402

MARGINS = (0.02, 0.01, 0.005, 0.0, None)
"""pipeline.margin values tried (0.01: the default since 2026-12-05, 0.02 before; None: the paper's test, similar
when the interval holds 0)"""
PICKS = (("front_pick", "prog-retrained"), ("det_front_pick", "det-prog-retrained"))
"""each family's front choice in a result file and the baseline its pick is evaluated as (det-prog's where the run
made its own front: re-picked at prog's validation-best, as stages/front_select reads it)"""


def candidate_rows(res: dict, cand: dict, baseline: str = "prog-retrained") -> list[dict]:
    """A candidate's per-seed test rows, evaluated now if the run has not (its retrained model is reused): the run's
    own command line (its task, budget, seed and config folder) as `neurosym eval` of ``baseline`` under the
    candidate's program."""
    cfg = res["front_pick"]["config"]
    path = Path(cfg["exp_dir"]) / "eval" / cand["label"] / "metrics.json"
    if not path.exists():
        args = [a for a in shlex.split(res["command"])[2:]
                if not a.startswith(("baselines=", "plots=", "progress=", "runs_root="))]
        cmd = [str(Path(sys.executable).parent / "neurosym"), "eval", *args, f"baseline={baseline}",
               f"program={cand['program_file']}", f"runs_root={cfg['runs_root']}", "plots=false", "progress=plain"]
        p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        if p.returncode != 0 or not path.exists():
            sys.exit(f"front_margin: evaluating {cand['label']} failed: {p.stderr.strip()[-300:]}")
    return json.loads(path.read_text())["per_seed"]


def as_baseline(label: str, rows: list[dict]) -> dict:
    """Per-seed test rows -> a baseline entry of the variant format ``claims`` reads (seed_variant's)."""
    summary = {}
    for k in (k for k in METRICS if k in rows[0]):  # a task without collisions records none
        xs = [r[k] for r in rows]
        m = sum(xs) / len(xs)
        summary[k] = {"mean": m, "std": (sum((x - m) ** 2 for x in xs) / (len(xs) - 1)) ** 0.5}
    return {"label": label, "summary": summary, "cost_per_seed": {str(r["seed"]): r["cost"] for r in rows}}


def judge_paper(directory: Path):
    """(task, seed, result, claims with some baselines' entries replaced) for every paper task-seed: the paper's
    claims."""
    for task, runs in sorted(load_seeds(directory).items()):
        for r in sorted(runs, key=lambda r: r.seed):
            v = seed_variant(r)

            def holds(entries: dict, v=v, task=task) -> dict:
                return {c.name: bool(c.holds) for c in claims(task, dict(v, baselines=dict(v["baselines"],
                                                                                          **entries)))}
            yield task, r.seed, json.loads(Path(r.source).read_text()), holds


def judge_beyond(directory: Path):
    """The same for the tasks beyond the paper: issue 37's four tests (beyond_paper.verdict)."""
    for f in sorted(directory.glob("*-seed*.json")):
        res = json.loads(f.read_text())

        def holds(entries: dict, res=res) -> dict:
            return verdict(dict(res, baselines=dict(res["baselines"], **entries)))["holds"]
        yield res["task"], res["seed"], res, holds


def run(judged) -> list[dict]:
    """One row per (task, training seed, margin): prog's pick (and det-prog's, where the run made its own front), its
    validation and test figures, what holds with every pick made at that margin."""
    out = []
    for task, seed, res, holds in judged:
        fronts = {b: res.get(key) or {} for key, b in PICKS if (res.get(key) or {}).get("candidates")}
        if "prog-retrained" not in fronts:
            continue
        method = [c for c in fronts["prog-retrained"]["candidates"] if not c.get("excluded")]
        best = min(method, key=lambda c: sum(c["loss"]) / len(c["loss"]))["loss"]  # det-prog's is read at it
        if any(len(c["loss"]) != len(best) for f in fronts.values() for c in f["candidates"]):
            sys.exit(f"front_margin: {task} seed {seed}: the fronts were validated on different numbers of seeds")
        for margin in MARGINS:
            entries, picked = {}, {}
            for baseline, front in fronts.items():
                cands = front["candidates"]
                rows = [{"name": c["name"], "loss": c["loss"], "degree": c["degree"]} for c in cands]
                chosen = next(c for c in pick([dict(x) for x in rows], helps=front["communication_helps"],
                                              margin=margin, reference=None if baseline == "prog-retrained" else best)
                              if c.get("picked"))
                cand = next(c for c in cands if c["name"] == chosen["name"])
                tests = candidate_rows(res, cand, baseline)
                entries[baseline] = dict(as_baseline(cand["label"], tests), per_seed=tests)
                picked[baseline] = cand
            mine, entry = picked["prog-retrained"], entries["prog-retrained"]
            out.append({"task": task, "seed": seed, "margin": margin, "pick": mine["name"],
                        "val_loss": mine["loss_mean"], "val_degree": mine["degree"],
                        "test_loss": entry["summary"]["cost"]["mean"],
                        "test_max_degree": entry["summary"]["max_degree"]["mean"],
                        **({"det_pick": picked["det-prog-retrained"]["name"],
                            "det_test_loss": entries["det-prog-retrained"]["summary"]["cost"]["mean"],
                            "det_test_max_out": entries["det-prog-retrained"]["summary"]["max_out"]["mean"]}
                           if "det-prog-retrained" in picked else {}),
                        "holds": {k: bool(h) for k, h in holds(entries).items()}})
            print(f"{task} seed {seed} margin {margin}: {mine['name']:6s} test loss {out[-1]['test_loss']:.3f} max "
                  f"in+out {out[-1]['test_max_degree']:.2f}"
                  + (f"; det-prog {out[-1]['det_pick']}" if "det_pick" in out[-1] else "") + "; fails: "
                  + (", ".join(k for k, h in out[-1]["holds"].items() if not h) or "none"), flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--suite", default="paper", choices=list(SUITES), help="which result files (beyond_paper's suites)")
    ap.add_argument("--json", default="", help="also write the rows here")
    a = ap.parse_args()
    out = SUITES[a.suite].out
    rows = run(judge_paper(out) if a.suite == "paper" else judge_beyond(out))
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
