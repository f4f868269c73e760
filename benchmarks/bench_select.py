"""Time to a good program: the paper's 10k-step chains vs the selection's schedule (coarse restarts + patience).

    python benchmarks/bench_select.py --exp outputs/random-cross/paper/seed0          # an oracle with its dataset D
    python benchmarks/bench_select.py --exp ... --rules 2 5 --seeds 3 --json out.json --plot out.png

Both schedules search the same dataset D (the run directory's synth/dataset-*.pt) with the same objective, one
process and one thread per search, ``--workers`` searches at a time (the two schedules alternate, so both see the
same load). Every point of a curve is the best objective on the whole of D reached by that wall time; a coarse
restart's best is scored on the whole of D when the restart ends, so its curve only moves then. Prints per
schedule the wall time, proposals and final objective, and the time each schedule needs to reach the paper
chain's median final objective.
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

SCHEDULES = {
    "paper": {"steps": 10_000, "patience": 0, "coarse": 1},  # the reference's chains (budget=paper, synth defaults)
    "select": {"steps": 10_000, "patience": 500, "coarse": 4},  # conf/select.yaml
}


def one(exp: str, schedule: str, rules: int, lam: float, features: str, seed: int) -> dict:
    import torch

    from neurosym_cli.run import checkpoints
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.dsl.sampling import SearchSpace, propose, random_rules
    from neurosym_cli.tasks import make_task
    from neurosym_cli.synth.dataset import FORMAT, from_payload, subsample
    from neurosym_cli.synth.mcmc import metropolis
    from neurosym_cli.run.layout import MODEL, ORACLE_DIR, RunFolder
    from neurosym_cli.synth.objective import CachedScorer
    from neurosym_cli.synth.search import feature_quantiles

    torch.set_num_threads(1)
    task = Path(exp).parts[-3]
    cfg = compose_config("synth", [f"task={task}"])
    sch = SCHEDULES[schedule]
    t0 = time.perf_counter()
    payload = checkpoints.load_checkpoint(RunFolder(exp).trained_dir(ORACLE_DIR) / MODEL, "neurosym train")
    policy = checkpoints.policy_from_payload(payload).eval()
    env = make_task(cfg.task)
    data_file = RunFolder(exp).datasets()[0]
    data = from_payload(checkpoints.load_payload(data_file, "neurosym synth", FORMAT, "dataset"))
    cpu = torch.device("cpu")

    def scorer(d, g):
        return CachedScorer(policy, env, d, round_idx=cfg.task.rounds - 1, version=features, lam=lam, objective="paper",
                            cap=rules, samples=1, gen=torch.Generator().manual_seed(g), device=cpu)

    full = scorer(data, 1)
    coarse = scorer(subsample(data, sch["coarse"]), 2) if sch["coarse"] > 1 else None
    space = SearchSpace(feature_quantiles(full, torch.Generator().manual_seed(3)), rules, 2, False, True)
    rng = random.Random(f"{seed}")
    curve = [[time.perf_counter() - t0, float("inf")]]

    def on_step(step, res, row):
        if row["best"] < curve[-1][1] - 1e-12:
            curve.append([time.perf_counter() - t0, row["best"]])

    res = metropolis(lambda: random_rules(space, rng), lambda r: propose(r, space, rng), full, steps=sch["steps"],
                     restarts=4, final_fraction=0.2, temperature=0.1, rng=rng, on_step=on_step,
                     patience=sch["patience"], coarse=coarse)
    total = time.perf_counter() - t0
    curve.append([total, res.best_score.total])
    return {"schedule": schedule, "rules": rules, "lam": lam, "features": features, "seed": seed, "seconds": total,
            "proposals": sum(res.proposed.values()), "best": res.best_score.total, "stopped": res.stopped,
            "states": full.total_states, "curve": curve[1:]}


def reach(curve: list, target: float) -> float | None:
    """Wall time at which a best-so-far curve first reaches ``target`` (None: never)."""
    return next((t for t, v in curve if v <= target + 1e-9), None)


def plot(runs: list[dict], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from neurosym_cli.viz.draw import save_figure

    ks = sorted({r["rules"] for r in runs})
    fig, axes = plt.subplots(1, len(ks), figsize=(5.5 * len(ks), 4.2), squeeze=False)
    colors = {"paper": "tab:gray", "select": "tab:blue"}
    for ax, k in zip(axes[0], ks):
        for r in (r for r in runs if r["rules"] == k):
            t = [p[0] for p in r["curve"]]
            v = [p[1] for p in r["curve"]]
            ax.step(t, v, where="post", color=colors[r["schedule"]], alpha=0.8,
                    label=f"{r['schedule']} ({SCHEDULES[r['schedule']]['steps']} steps"
                          + (f", coarse {SCHEDULES[r['schedule']]['coarse']}, patience "
                             f"{SCHEDULES[r['schedule']]['patience']}" if r["schedule"] != "paper" else "") + ")")
        finals = [r["best"] for r in runs if r["rules"] == k]
        target = statistics.median(r["best"] for r in runs if r["rules"] == k and r["schedule"] == "paper")
        ax.axhline(target, color="0.3", ls=":", lw=1, label=f"the paper chains' median final ({target:.3f})")
        lo, hi = min(finals), max(finals)
        ax.set_ylim(lo - 0.1 * (hi - lo + 0.1), lo + 3 * (hi - lo + 0.1))
        ax.set_xlabel("wall time (s, one core)")
        ax.set_ylabel("best objective on the whole of D (lower is better)")
        seeds = len({r["seed"] for r in runs if r["rules"] == k})
        ax.set_title(f"K = {k}, lam = {runs[0]['lam']:g}, {seeds} search seeds per schedule", fontsize=10)
        handles, labels = ax.get_legend_handles_labels()
        keep = dict(zip(labels, handles))
        ax.legend(keep.values(), keep.keys(), fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--exp", required=True, help="run directory with train/oracle/model.pt and synth/dataset-*.pt")
    ap.add_argument("--rules", type=int, nargs="+", default=[2, 5])
    ap.add_argument("--lam", type=float, default=0.5)
    ap.add_argument("--features", default="v1")
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", default="")
    ap.add_argument("--plot", default="")
    ap.add_argument("--replot", default="", metavar="JSON", help="only redraw --plot from a saved --json file")
    a = ap.parse_args()
    if a.replot:
        saved = json.loads(Path(a.replot).read_text())
        runs = saved["runs"]
        plot(runs, Path(a.plot), f"time to quality on {Path(saved['exp']).parts[-3]} ({runs[0]['states']} states in "
                                 "D): the paper's chains vs the selection's schedule")
        return
    jobs = [(a.exp, s, k, a.lam, a.features, seed) for k in a.rules for seed in range(a.seeds) for s in SCHEDULES]
    with ProcessPoolExecutor(a.workers, mp_context=get_context("spawn")) as pool:
        runs = list(pool.map(one, *zip(*jobs)))
    for k in a.rules:
        rs = [r for r in runs if r["rules"] == k]
        target = statistics.median(r["best"] for r in rs if r["schedule"] == "paper")
        print(f"K={k} lam={a.lam:g} {a.features}: target = the paper chains' median final objective {target:.4f}")
        for s in SCHEDULES:
            mine = [r for r in rs if r["schedule"] == s]
            hit = [reach(r["curve"], target) for r in mine]
            print(f"  {s:<7} wall {statistics.mean(r['seconds'] for r in mine):6.1f} s  proposals "
                  f"{statistics.mean(r['proposals'] for r in mine):7.0f}  final "
                  + " ".join(f"{r['best']:.4f}" for r in mine)
                  + "  reaches the target at " + " ".join("never" if h is None else f"{h:.0f} s" for h in hit))
    if a.json:
        Path(a.json).write_text(json.dumps({"exp": a.exp, "schedules": SCHEDULES, "runs": runs}, indent=1))
    if a.plot:
        plot(runs, Path(a.plot), f"time to quality on {Path(a.exp).parts[-3]} ({runs[0]['states']} states in D): "
                                 f"the paper's chains vs the selection's schedule")


if __name__ == "__main__":
    main()
