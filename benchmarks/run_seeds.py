"""Training seeds as the runs: the paper protocol with model selection, per task and training seed, resumable.

    python benchmarks/run_seeds.py                          # seeds 0 1 2 of random-cross, random-grid, unlabeled-goals
    python benchmarks/run_seeds.py --tasks random-grid --seeds 1 2
    python benchmarks/run_seeds.py --budget tiny --out /tmp/seeds --runs /tmp/runs   # a quick dry rehearsal
    python benchmarks/run_seeds.py --commit                 # git-commit each task-seed's result file as it lands

For every (seed, task) in that order, the commands a user would type (docs/results.md, 'Model selection'):
``neurosym train task=T budget=B seed=S`` (the oracle), ``neurosym select ...`` (the paper's 32-point grid on its
dataset, with select's search schedule) and ``neurosym pipeline ... selected=true`` (every baseline with the
picked K, lambda, features and search settings), with pinned CPU kernels (``ATEN_CPU_CAPABILITY=avx2``,
``MKL_CBWR=AVX2`` before torch loads: the same numbers on AVX2 and AVX-512 machines, docs/performance.md).
When it ends, the small result file ``docs/results/seeds/<task>-seed<S>.json`` is written from the run
directory: each baseline's evaluation (summary and per-evaluation-seed rows), the pick and the selection's table,
the programs, the stage times and the machine. A task-seed whose result file exists is skipped; an interrupted
one resumes (every stage of the pipeline resumes from its checkpoints). Run directories are not kept between
sessions, and one task-seed at the paper budget takes longer than a session on a busy 2-core machine, so the small
resumable artifacts of an unfinished task-seed (the oracle's checkpoint and history, each searched program with its
summary, select's validations, retrained models, evaluations; no datasets, traces or logs: under 1 MB) are stashed
under ``<out>/partial/<task>-seed<S>/`` every ``--stash-every`` seconds and committed with ``--commit``; the next
session's runner copies them back and goes on from there, and the stash is removed when the result file lands.
``--stash-only`` does just the stashing, for runs already going; ``--recollect`` writes result files again from run
directories still on disk (after a fix in what ``collect`` keeps).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

from neurosym_cli.run.layout import ORACLE_DIR, TRACE, RunFolder
from neurosym_cli.schemes import SCHEMES
from neurosym_cli.schemes.searched import Searched, program_tag, tag_prefixes  # Searched: under a program or tree
from neurosym_cli.utils.io import write_json
from neurosym_cli.utils.cpu import PIN  # what the pinned modes set (the console script sets it in every job too)

ROOT = Path(__file__).resolve().parent.parent
TASKS = ("random-cross", "random-grid", "unlabeled-goals")
SEEDS = (0, 1, 2)
"""the training seeds the protocol runs per task (docs/results.md reads both from here)"""
PAPER_METHOD = ("synth.search=mcmc", "synth.front=false", "pipeline.select=none")
"""the paper's method (MCMC, the single-lambda program), the defaults before issue 37: what the committed result
files ran, so the protocol keeps reproducing them; --defaults runs today's defaults instead"""
KEEP_SELECT = ("name", "lam", "rules", "features", "objective", "l1", "degree_term", "loss", "degree", "max_in",
               "max_out")


def neurosym() -> str:
    """The console script beside this interpreter (a venv's bin/), else the one on PATH."""
    here = Path(sys.executable).parent / "neurosym"
    return str(here) if here.exists() else "neurosym"


def result_file(out: Path, task: str, seed: int) -> Path:
    return out / f"{task}-seed{seed}.json"


def collect(exp: Path, task: str, seed: int, budget: str, wall_s: float) -> dict:
    """The small result file of one task-seed from its run directory (the pipeline's evaluations under the pick)."""
    run = RunFolder(exp)
    selected = json.loads(run.selected_file.read_text())
    selection = json.loads(run.selection_file().read_text())
    pick = {k: selected[k] for k in ("rules", "lam", "features") if k in selected}
    baselines: dict[str, dict] = {}
    for f in run.metrics_files():
        m = json.loads(f.read_text())
        c = m["config"]
        if c["rules"] != pick["rules"] or c.get("program"):
            # another K (the selection's own evaluations of other grid points), or a hand-written program; the
            # config's K, not the metrics' (a searched program simplified to fewer rules records its own count)
            continue
        if isinstance(SCHEMES.get(m["baseline"]), Searched) and (c["lam"] != pick["lam"]
                                                              or c["features"] != pick["features"]):
            continue
        if m["label"] != m["baseline"] and m["label"].split("-k")[0] != m["baseline"]:
            continue  # rl1/rl2 and other renamed rows
        baselines[m["baseline"]] = {"label": m["label"], "summary": m["summary"], "per_seed": m["per_seed"],
                                    "seconds": m["seconds"]}
    tag = program_tag(rules=pick["rules"], lam=pick["lam"], features=pick["features"], synth=selected["synth"])
    programs = {p.parent.name: p.read_text().strip() for p in run.programs()
                if p.parent.name in {prefix + tag for prefix in tag_prefixes()}}  # the pick's prog and det-prog
    timings = run.timings_file
    return {
        "task": task, "seed": seed, "budget": budget, "pick": pick, "selected": selected,
        "selection": [{k: r.get(k) for k in KEEP_SELECT} for r in selection["programs"]],
        "retrained_finalists": selection.get("retrained", []),
        "baselines": baselines, "programs": programs,
        "timings": json.loads(timings.read_text()) if timings.exists() else {},
        "wall_s": round(wall_s, 1),
        "machine": {**machine(exp), "pin": PIN, "python": platform.python_version(),
                    "processor": platform.processor() or platform.machine(), "cores": os.cpu_count()},
    }


def machine(exp: Path) -> dict:
    """What the oracle of a run directory trained with (its manifest's runtime record): the cpu_kernels mode, MKL's
    path, the CPU's vendor and model, the torch version."""
    rt = json.loads(RunFolder(exp).manifest_of(ORACLE_DIR).read_text()).get("runtime") or {}
    return {k: rt.get(k) for k in ("cpu_kernels", "mkl_path", "cpu_vendor", "cpu", "torch")}


STASH_MAX = 1 << 20
"""bytes: a stashed artifact is at most this big (datasets are remade from the oracle; traces and logs are not needed
to resume)"""
SKIP = ("logs", ".lock", TRACE)


def stash_dir(out: Path, task: str, seed: int) -> Path:
    return out / "partial" / f"{task}-seed{seed}"


def stash(exp: Path, dest: Path) -> int:
    """Copy the small resumable artifacts of a run directory to ``dest`` (atomically per file, only what changed);
    the number of files copied."""
    n = 0
    if not exp.is_dir():
        return 0
    for f in sorted(exp.rglob("*")):
        rel = f.relative_to(exp)
        if not f.is_file() or any(p in SKIP for p in rel.parts) or f.name.startswith("dataset") \
                or f.suffix == ".tmp" or f.stat().st_size > STASH_MAX:
            continue
        to = dest / rel
        data = f.read_bytes()
        if to.exists() and to.read_bytes() == data:
            continue
        to.parent.mkdir(parents=True, exist_ok=True)
        tmp = to.with_name(to.name + ".tmp")
        tmp.write_bytes(data)
        tmp.replace(to)
        n += 1
    return n


def restore(src: Path, exp: Path) -> int:
    """Copy a stash back into a run directory, keeping any file the run directory already has; files copied."""
    n = 0
    for f in sorted(src.rglob("*")) if src.is_dir() else []:
        to = exp / f.relative_to(src)
        if f.is_file() and not to.exists():
            to.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(f, to)
            n += 1
    return n


def git_commit(path: Path, message: str) -> None:
    cwd = next(p for p in path.parents if p.exists())  # git rm takes emptied folders with it
    for attempt in range(20):  # another process may hold the index lock for a moment
        if path.exists():  # new files of a stash, or the result file; a removed stash is staged by git rm already
            subprocess.run(["git", "add", "--", str(path)], cwd=cwd, capture_output=True, check=False)
        r = subprocess.run(["git", "commit", "-q", "-m", message, "--", str(path)], cwd=cwd, capture_output=True,
                           text=True)
        if r.returncode == 0 or "nothing" in r.stdout + r.stderr:
            return
        time.sleep(3)
    print(f"could not commit {path}", file=sys.stderr)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tasks", nargs="+", default=list(TASKS))
    ap.add_argument("--seeds", nargs="+", type=int, default=list(SEEDS))
    ap.add_argument("--budget", default="paper")
    ap.add_argument("--jobs", type=int, default=0, help="select.jobs (0 = one per CPU)")
    ap.add_argument("--runs", default=str(ROOT / "outputs"), help="runs root")
    ap.add_argument("--out", default=str(ROOT / "docs" / "results" / "seeds"), help="where result files go")
    ap.add_argument("--commit", action="store_true", help="git-commit each result file as it is written")
    ap.add_argument("--defaults", action="store_true", help="today's defaults (hybrid search, the pick among the "
                    "front) instead of the paper's method the committed files ran (PAPER_METHOD)")
    ap.add_argument("--extra", nargs="*", default=[], help="more overrides for every pipeline (tiny rehearsals)")
    ap.add_argument("--stash-every", type=float, default=600.0, help="seconds between stashes of an unfinished "
                    "task-seed's resumable artifacts (0 = never)")
    ap.add_argument("--stash-only", action="store_true", help="only stash (and commit) the given task-seeds' run "
                    "directories every --stash-every seconds, until interrupted")
    ap.add_argument("--recollect", action="store_true", help="write the given task-seeds' result files again from "
                    "their run directories (kept wall time and machine), where both exist, and run nothing")
    args = ap.parse_args()
    out, runs = Path(args.out), Path(args.runs)
    if args.recollect:
        for seed in args.seeds:
            for task in args.tasks:
                recollect(out, runs, task, seed, args)
        return
    if args.stash_only:
        while True:
            for seed in args.seeds:
                for task in args.tasks:
                    keep_stash(out, runs, task, seed, args)
            time.sleep(args.stash_every)
    out.mkdir(parents=True, exist_ok=True)
    logs = runs / "logs" / "seeds"
    logs.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, **PIN}
    for seed in args.seeds:
        for task in args.tasks:
            dest = result_file(out, task, seed)
            if dest.exists():
                print(f"{task} seed {seed}: done ({dest})", flush=True)
                continue
            common = [f"task={task}", f"budget={args.budget}", f"seed={seed}", "threads=1", "plots=false",
                      *(() if args.defaults else PAPER_METHOD),
                      "progress=plain", f"runs_root={runs}"]
            cmds = [[neurosym(), "train", *common],
                    [neurosym(), "select", *common, f"select.jobs={args.jobs}", *args.extra],
                    [neurosym(), "pipeline", *common, "selected=true"]]
            exp = runs / task / args.budget / f"seed{seed}"
            back = restore(stash_dir(out, task, seed), exp)
            if back:
                print(f"{task} seed {seed}: {back} stashed artifacts restored from {stash_dir(out, task, seed)}",
                      flush=True)
            stop = threading.Event()
            keeper = threading.Thread(target=_keep, args=(stop, out, runs, task, seed, args), daemon=True)
            if args.stash_every > 0:
                keeper.start()
            t0 = time.time()
            rc = 0
            with open(logs / f"{task}-seed{seed}.log", "a") as log:
                for cmd in cmds:
                    print(f"{time.strftime('%H:%M:%S')} {task} seed {seed}: {' '.join(cmd)}", flush=True)
                    log.flush()
                    rc = subprocess.run(cmd, env=env, stdout=log, stderr=subprocess.STDOUT).returncode
                    if rc:
                        break
            stop.set()
            if rc != 0:
                keep_stash(out, runs, task, seed, args)
                print(f"{task} seed {seed}: exit {rc}; see {logs / (task + f'-seed{seed}.log')}", flush=True)
                continue
            res = collect(exp, task, seed, args.budget, time.time() - t0)
            write_result(dest, res)
            print(f"{time.strftime('%H:%M:%S')} {task} seed {seed}: {len(res['baselines'])} baselines, pick "
                  f"{res['pick']} in {res['wall_s'] / 60:.1f} min -> {dest}", flush=True)
            if args.commit:
                git_commit(dest, f"docs/results/seeds: {task} training seed {seed} ({args.budget} budget, "
                                 f"pinned kernels)")
            part = stash_dir(out, task, seed)
            if part.exists():
                if args.commit:
                    subprocess.run(["git", "rm", "-r", "-q", "--", str(part)], cwd=out, check=False)
                    git_commit(part, f"docs/results/seeds: {task} training seed {seed} done; its stash removed")
                shutil.rmtree(part, ignore_errors=True)


def write_result(dest: Path, res: dict) -> None:
    """A result file (here and docs/results/, benchmarks/results/files.py), atomically, with a temp file of its own
    (concurrent writers never share one); sorted keys and a one-space indent keep its diffs in git small."""
    write_json(dest, res, indent=1, sort_keys=True)


def recollect(out: Path, runs: Path, task: str, seed: int, args) -> None:
    """A result file written again from its run directory by this ``collect`` (a fix in what it keeps), with the
    wall time and machine of the run that made it."""
    dest, exp = result_file(out, task, seed), runs / task / args.budget / f"seed{seed}"
    if not (dest.exists() and RunFolder(exp).selected_file.exists()):
        print(f"{task} seed {seed}: nothing to collect again (no result file or no run directory)", flush=True)
        return
    old = json.loads(dest.read_text())
    res = {**collect(exp, task, seed, args.budget, old["wall_s"]), "machine": old["machine"]}
    if res == old:
        print(f"{task} seed {seed}: unchanged", flush=True)
        return
    write_result(dest, res)
    print(f"{task} seed {seed}: collected again, {len(res['baselines'])} baselines (was {len(old['baselines'])})",
          flush=True)
    if args.commit:
        git_commit(dest, f"docs/results/seeds: {task} training seed {seed} collected again")


def keep_stash(out: Path, runs: Path, task: str, seed: int, args) -> None:
    """Stash one task-seed's run directory (unless its result file exists) and commit what changed."""
    if result_file(out, task, seed).exists():
        return
    part = stash_dir(out, task, seed)
    n = stash(runs / task / args.budget / f"seed{seed}", part)
    if n:
        print(f"{time.strftime('%H:%M:%S')} {task} seed {seed}: {n} artifacts stashed in {part}", flush=True)
        if args.commit:
            git_commit(part, f"docs/results/seeds: stash of unfinished {task} training seed {seed} "
                             f"({args.budget} budget)")


def _keep(stop: threading.Event, out: Path, runs: Path, task: str, seed: int, args) -> None:
    while not stop.wait(args.stash_every):
        keep_stash(out, runs, task, seed, args)


if __name__ == "__main__":
    main()
