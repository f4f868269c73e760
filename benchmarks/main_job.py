"""The README's main job over training seeds: run it, then collect its small result files.

    neurosym pipeline task=two-groups-cross -m seed=0,1,2,3,4,5,6,7,8,9 runs_root=/tmp/mainjob   # about 3 min a seed
    python benchmarks/main_job.py /tmp/mainjob                                         # docs/results/main-job/

The defaults since issue 37 (the hybrid search, the degree-budget front and the pipeline's pick among it) make the
main job; seeds can be collected across sessions (seeds already in seeds.json stay when the command matches; run
directories are not kept between sessions). The paper's method, as docs/results/main-job-paper-method/ ran it on
2026-12-03 (two threads then: threads=0 on 2 cores):

    neurosym pipeline task=two-groups-cross -m seed=0,1,2 synth.search=mcmc synth.front=false pipeline.select=none \
        threads=2 runs_root=/tmp/mjp
    python benchmarks/main_job.py /tmp/mjp --out docs/results/main-job-paper-method \
        --figure /tmp/mjp/seeds.png --command "synth.search=mcmc synth.front=false pipeline.select=none threads=2"

Writes docs/results/main-job/seeds.json (per training seed: each baseline's summary over the 20 evaluation seeds,
the programs, the stage timings), report.json, report.csv and improvement.csv (`neurosym report` across the seeds,
copied from the runs root) and docs/figures/main-job-seeds.png (the loss-degree plane over the seeds), and prints
the figures the README quotes.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shutil
import subprocess
import sys
from pathlib import Path

from neurosym_cli.run.layout import (IMPROVEMENT_CSV, REPORT_CSV, REPORT_JSON, RunFolder, RunsRoot, seed_dir,
                                     seeds_plane_file)

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "results" / "main-job"
TASK, BUDGET = "two-groups-cross", "quick"
QUOTED = ("tf-full", "prog-retrained", "det-prog-retrained", "hard-attn", "dist", "no-comm")


def seed_record(exp: Path) -> dict:
    """One training seed's run directory -> its baselines' summaries, programs and stage timings."""
    baselines = {}
    run = RunFolder(exp)
    for f in run.metrics_files():
        m = json.loads(f.read_text())
        baselines[m["label"]] = {k: {x: round(v[x], 5) if isinstance(v[x], float) else v[x]
                                     for x in ("mean", "std", "ci95", "n")} for k, v in m["summary"].items()}
    programs = {p.parent.name: [line for line in p.read_text().splitlines() if line and not line.startswith("#")]
                for p in run.programs()}
    timings = run.timings_file
    picks = {}
    for f in sorted((exp / "select" / "front").glob("*.json")):  # the pipeline's pick among the front
        c = json.loads(f.read_text())
        picks[c["tag"]] = {"budget": c["picked"]["budget"], "program": c["picked"]["program"].splitlines(),
                           "validation_loss": round(c["picked"]["loss_mean"], 5),
                           "validation_max_in_out": round(c["picked"]["degree"], 5),
                           "communication_helps": c["communication_helps"], "margin": c.get("margin")}
    return {"baselines": baselines, "programs": programs, "front_picks": picks,
            "timings": json.loads(timings.read_text()) if timings.exists() else {}}


def finished(exp: Path) -> bool:
    """Has every quoted baseline of this seed's run directory an evaluation (its pipeline got that far)?"""
    labels = {f.parent.name for f in RunFolder(exp).metrics_files()}
    return all(label_of(dict.fromkeys(labels), b) for b in QUOTED)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs_root", help="the runs root the main job ran in")
    ap.add_argument("--out", default=str(OUT), help="where the small result files go (default docs/results/main-job)")
    ap.add_argument("--figure", default=str(ROOT / "docs" / "figures" / "main-job-seeds.png"),
                    help="where the seeds' loss-degree plane goes")
    ap.add_argument("--command", default="", help="the pipeline's overrides beyond task and seed, as run (recorded)")
    a = ap.parse_args()
    out = Path(a.out)
    base = Path(a.runs_root) / TASK / BUDGET
    seeds = sorted(k for p in base.iterdir() if (k := RunsRoot.parse_seed_dir(p.name)) is not None
                   and finished(p)) if base.is_dir() else []
    if not seeds:
        raise SystemExit(f"no seed directories under {base}; run: neurosym pipeline task={TASK} -m seed=0,1,2 "
                         f"runs_root={a.runs_root}")
    env = {**os.environ, "NEUROSYM_RUNS": str(a.runs_root)}
    p = subprocess.run([sys.executable, "-m", "neurosym_cli.cli", "report", f"task={TASK}", f"budget={BUDGET}",
                        f"runs_root={a.runs_root}"], env=env, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"neurosym report failed: {p.stderr.strip().splitlines()[-1:]}")
    out.mkdir(parents=True, exist_ok=True)
    for name in (REPORT_JSON, REPORT_CSV, IMPROVEMENT_CSV):
        shutil.copyfile(base / name, out / name)
    shutil.copyfile(base / seeds_plane_file(TASK), Path(a.figure))
    from run_seeds import machine  # the oracle manifest's runtime record (this script's folder is on sys.path)

    record = {"command": f"neurosym pipeline task={TASK} -m seed={','.join(map(str, seeds))} {a.command}".strip(),
              "date": datetime.date.today().isoformat(),
              "machine": {**machine(base / seed_dir(seeds[0])), "cores": os.cpu_count(),
                          "processor": platform.machine(), "threads": threads_of(base / seed_dir(seeds[0]))},
              "note": "per training seed: each baseline's summary over 20 evaluation seeds (mean, std ddof 1, "
                      "ci95 = 95 % t half-width, n)",
              "seeds": {str(s): seed_record(base / seed_dir(s)) for s in seeds}}
    old = out / "seeds.json"
    if old.exists():  # seeds run in earlier sessions (run directories are not kept between them) stay
        before = json.loads(old.read_text())
        kept = {s: r for s, r in before.get("seeds", {}).items() if s not in record["seeds"]}
        if kept and before.get("command", "").split(" -m ")[-1].split(" ", 1)[1:] == \
                record["command"].split(" -m ")[-1].split(" ", 1)[1:]:
            record["seeds"] = dict(sorted({**kept, **record["seeds"]}.items(), key=lambda kv: int(kv[0])))
            record["report_covers"] = [str(s) for s in seeds]  # report.json: the seeds of this runs root only
    (out / "seeds.json").write_text(json.dumps(record, indent=1, sort_keys=True) + "\n")
    across = json.loads((out / REPORT_JSON).read_text())["tasks"][TASK]["baselines"]
    print(f"wrote {out}/ and {a.figure}")
    print(f"loss per seed {' / '.join(map(str, seeds))}; across seeds mean ± 95 % t half-width, max in per seed")
    for b in QUOTED:
        per, deg = [], []
        for s in seeds:
            m = record["seeds"][str(s)]["baselines"]
            label = label_of(m, b)
            per.append(f"{m[label]['cost']['mean']:.3f}" if label else "-")
            deg.append(f"{m[label]['max_in']['mean']:.2f}" if label else "-")
        c = across.get(b, {}).get("cost")
        ci = f" ± {c['ci95']:.2f}" if c and c.get("ci95") is not None else " (one seed: no interval)"
        print(f"  {b:20s} {' / '.join(per)}   across {c['mean']:.2f}{ci}   max in {' / '.join(deg)}"
              if c else f"  {b:20s} {' / '.join(per)}")
    near = within(record, "prog-retrained", "tf-full", 0.05)
    print(f"prog-retrained within 5 % of tf-full's loss on {sum(near.values())} of {len(near)} seeds "
          f"({', '.join(str(s) for s, ok in near.items() if not ok) or 'none'} outside)")


def threads_of(exp: Path) -> str:
    """The torch thread count the oracle of a run directory trained with, as its manifest's config recorded it."""
    manifest = json.loads(RunFolder(exp).manifest_of("oracle").read_text())
    n = (manifest.get("config") or {}).get("threads")
    return "0 (torch's default: the cores)" if n == 0 else str(n) if n is not None else "unrecorded"


def label_of(baselines: dict, name: str) -> str | None:
    """The evaluation label of baseline ``name`` in one seed's record (labels carry k, the program's tag or its
    content after the name)."""
    return next((k for k in baselines if k == name or k.startswith(name + "-k") or k.startswith(name + "-")
                 and not any(k.startswith(o + "-") for o in QUOTED if o != name and o.startswith(name))), None)


def within(record: dict, a: str, b: str, frac: float) -> dict[str, bool]:
    """Per seed: is baseline ``a``'s mean loss at most (1 + frac) x ``b``'s?"""
    out = {}
    for s, r in record["seeds"].items():
        la, lb = label_of(r["baselines"], a), label_of(r["baselines"], b)
        if la and lb:
            out[s] = r["baselines"][la]["cost"]["mean"] <= (1 + frac) * r["baselines"][lb]["cost"]["mean"]
    return out

if __name__ == "__main__":
    main()
