"""MCMC (synth.search=mcmc) against the hybrid local search (synth.search=hybrid) at equal wall time.

    neurosym train task=two-groups-cross budget=tiny runs_root=/tmp/bs          # an oracle per task, once
    python benchmarks/bench_search.py --runs-root /tmp/bs                        # the four paper tasks and the ring
    python benchmarks/bench_search.py --tasks ring --seeds 0 --steps 300         # a quick look

For each task, D is collected as `neurosym synth` collects it, from the oracle under --runs-root, with --rollouts
rollouts at the task's own horizon (budget=quick's D; a tiny budget's D has a handful of states). For each search
seed, MCMC runs the configured schedule of --steps proposals (synth's defaults: 4 restarts, final 20 %); its wall
time T is then the hybrid's budget (phases shared as the steps are). Each search gets a fresh scorer of the first
round (nothing cached from the other), after one warm-up scorer has compiled the kernels. Printed per task and seed:
the best objective each reached, evaluations to target (scored programs until each first reached MCMC's final
objective; '-' never), and proposals/s (scored programs per second; the hybrid's cache hits are not counted).

Measured (tiny oracles, D of 60 rollouts, 1,500 MCMC steps, search seeds 0-2, 2 shared CPU cores; mean best
objective MCMC -> hybrid, hybrid better in): two-groups-cross 4.591 -> 4.069 (3 of 3), random-cross 8.231 -> 7.355
(3 of 3), random-grid 12.456 -> 11.761 (3 of 3), unlabeled-goals 3.032 -> 2.761 (3 of 3), ring 1.000 -> 0.989
(3 of 3); median evaluations to MCMC's final objective: MCMC 1240, 1296, 954, 1227, 377; hybrid 173, 138, 450, 838,
117.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics
import sys
from pathlib import Path

import neurosym_cli  # noqa: F401  (before torch: pins the CPU kernels)
import torch

ROOT = Path(__file__).resolve().parents[1]
PAPER = ("two-groups-cross", "random-cross", "random-grid", "unlabeled-goals")
CONFIG_DIRS = {"ring": ROOT / "examples" / "ring" / "conf"}


def _reached(trace: list[dict], target: float) -> int | None:
    """The evaluation at which the trace's best first reached ``target`` (None: never)."""
    for row in trace:
        if row["best"] <= target + 1e-9 * max(1.0, abs(target)):
            return row["step"]
    return None


def bench_task(task: str, a: argparse.Namespace) -> list[dict]:
    from neurosym_cli import api
    from neurosym_cli.run.checkpoints import open_checkpoint, policy_from_payload
    from neurosym_cli.synth.dataset import collect
    from neurosym_cli.tasks import make_task
    from neurosym_cli.utils.device import resolve_device
    from neurosym_cli.synth.objective import CachedScorer
    from neurosym_cli.synth.search import RoundSpec, search_round
    from neurosym_cli.utils.seeding import STREAM_SYNTH, STREAM_SYNTH_DATA, generator

    cfg = api.compose("synth", task=task, baseline="prog", budget=a.budget, runs_root=a.runs_root, threads=a.threads,
                      config_dir=CONFIG_DIRS.get(task))
    torch.set_num_threads(a.threads)
    device = resolve_device(cfg.device)
    policy = policy_from_payload(open_checkpoint(cfg, oracle=True)).to(device).eval()
    env = make_task(cfg.task)  # the task's own horizon (a tiny budget shortens it to a handful of steps)
    data = collect(env, policy, a.rollouts, cfg.synth.stride, generator(cfg.seed, STREAM_SYNTH_DATA), device)

    def scorer() -> CachedScorer:
        return CachedScorer(policy, env, data, round_idx=0, version=cfg.features, lam=cfg.lam,
                            objective=cfg.synth.objective, cap=cfg.rules, samples=cfg.synth.random_samples,
                            gen=generator(cfg.seed, STREAM_SYNTH, 0), device=device, backend=cfg.synth.backend)

    base = RoundSpec(steps=a.steps, restarts=cfg.synth.restarts, final_fraction=cfg.synth.final_fraction,
                     temperature=cfg.synth.temperature, rules=cfg.rules, max_depth=cfg.synth.max_depth,
                     det=cfg.baseline.det, own_scores=cfg.synth.own_scores)
    search_round(scorer(), dataclasses.replace(base, steps=20), "warm-up", generator(0, STREAM_SYNTH, 100))
    rows = []
    for seed in a.seeds:
        gen = generator(cfg.seed, STREAM_SYNTH, 100)
        m = search_round(scorer(), base, f"{seed}/0/bench", gen)
        hyb = dataclasses.replace(base, search="hybrid", steps=10**9, seconds=m.seconds)
        h = search_round(scorer(), hyb, f"{seed}/0/bench", generator(cfg.seed, STREAM_SYNTH, 100))
        target = m.best_score.total
        row = {"task": task, "seed": seed, "states": sum(b.states for b in data), "seconds": m.seconds,
               "mcmc_best": target, "hybrid_best": h.best_score.total,
               "mcmc_evals": sum(m.proposed.values()), "hybrid_evals": sum(h.proposed.values()),
               "mcmc_to_target": _reached(m.trace, target), "hybrid_to_target": _reached(h.trace, target),
               "mcmc_per_s": m.proposals_per_second, "hybrid_per_s": h.proposals_per_second,
               "hybrid_skipped": h.skipped}
        rows.append(row)
        print(f"{task:18s} seed {seed}  {row['seconds']:6.1f} s  best mcmc {target:8.4f}  hybrid "
              f"{row['hybrid_best']:8.4f}  evals-to-target mcmc {row['mcmc_to_target'] or '-':>6}  hybrid "
              f"{row['hybrid_to_target'] or '-':>6}  proposals/s mcmc {row['mcmc_per_s']:6.0f}  hybrid "
              f"{row['hybrid_per_s']:6.0f}  (hybrid skipped {h.skipped} known programs)", flush=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=[*PAPER, "ring"])
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2], help="search seeds")
    ap.add_argument("--steps", type=int, default=1500, help="MCMC proposals; its wall time is the hybrid's budget")
    ap.add_argument("--budget", default="tiny", help="the oracle's budget (train the oracle first)")
    ap.add_argument("--rollouts", type=int, default=60, help="rollouts of D (budget=quick's synth_rollouts), "
                                                             "at the task's horizon and synth.stride")
    ap.add_argument("--runs-root", default="/tmp/bs")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--json", default="", help="also write the rows here")
    a = ap.parse_args()
    from neurosym_cli.errors import UserError

    rows = []
    try:
        for task in a.tasks:
            rows += bench_task(task, a)
    except UserError as e:
        sys.exit(f"bench_search: {e}")
    print("\ntask                 mean best mcmc  mean best hybrid  hybrid better  median evals-to-target m/h")
    for task in a.tasks:
        rs = [r for r in rows if r["task"] == task]
        better = sum(r["hybrid_best"] < r["mcmc_best"] - 1e-9 for r in rs)
        med = [statistics.median([r[k] or float("inf") for r in rs]) for k in ("mcmc_to_target", "hybrid_to_target")]
        print(f"{task:18s}  {statistics.mean(r['mcmc_best'] for r in rs):14.4f}  "
              f"{statistics.mean(r['hybrid_best'] for r in rs):16.4f}  {better:>6d} of {len(rs)}  "
              f"{med[0]:>10.0f} / {med[1]:.0f}")
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=2))


if __name__ == "__main__":
    main()
