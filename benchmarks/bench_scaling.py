"""How cost grows with the number of agents N on a random-cross-like task (two groups of N/2 crossing).

    python benchmarks/bench_scaling.py                    # N = 10, 20, 40, 80, 160 (a few minutes)
    python benchmarks/bench_scaling.py --ns 10 20 --json out.json

Each N runs in its own process (so its peak memory is its own) and measures, with the same model:
  - training: batched BPTT rollouts/s (batch 4, T = 50, after a warm-up batch) and agent-steps/s;
  - evaluation: forward-only rollouts/s (batch 4, T = 50);
  - synthesis: on a dataset of 10 rollouts x 50 steps (500 states, 500 N^2 pairs), ms per MCMC proposal of
    the cached scorer vs seconds per proposal of the full-forward scorer, and their ratio;
  - peak resident memory of the process.
Start boxes grow with N (half-width 1.25 sqrt(N / 20)) so that N agents fit at the minimum separation.
"""

from __future__ import annotations

import argparse
import json
import math
import random
import resource
import subprocess
import sys
import time

import torch


def measure(n: int, threads: int) -> dict:
    from neurosym_cli.config import ModelConfig
    from neurosym_cli.tasks.random_cross import CrossConfig
    from neurosym_cli.dsl.ast import Program
    from neurosym_cli.dsl.sampling import SearchSpace, propose, random_rules
    from neurosym_cli.tasks import Rng, make_task
    from neurosym_cli.policy import CommTransformer, FullComm
    from neurosym_cli.rollout import rollout
    from neurosym_cli.synth.dataset import collect
    from neurosym_cli.synth.mcmc import metropolis
    from neurosym_cli.synth.objective import CachedScorer
    from neurosym_cli.synth.search import feature_quantiles
    from neurosym_cli.training import FitSpec, fit

    torch.set_num_threads(threads)
    cpu = torch.device("cpu")
    task = CrossConfig(name=f"cross-{n}", num_groups=2, agents_per_group=n // 2, group_prob=1.0,
                       box_half_width=1.25 * math.sqrt(n / 20), horizon=50)
    env = make_task(task)
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig())
    out: dict = {"n": n, "pairs_per_state": n * n}

    class Quiet:
        def update(self, step, total, metrics):
            pass

    batch = 4
    spec = FitSpec(rollouts=batch, batch=batch, horizon=50, checkpoint_every=10**9)
    fit(pol, env, FullComm(), spec, gen=torch.Generator().manual_seed(0), device=cpu,
        reporter=Quiet(), save=lambda s: None)  # warm-up
    spec = FitSpec(rollouts=3 * batch, batch=batch, horizon=50, checkpoint_every=10**9)
    t0 = time.perf_counter()
    fit(pol, env, FullComm(), spec, gen=torch.Generator().manual_seed(0), device=cpu,
        reporter=Quiet(), save=lambda s: None)
    train_s = (time.perf_counter() - t0) / spec.rollouts
    out.update(train_rollouts_per_s=1 / train_s, train_agent_steps_per_s=n * 50 / train_s)

    gen = torch.Generator().manual_seed(1)
    t0 = time.perf_counter()
    with torch.no_grad():
        for state in env.reset(batch, gen):
            rollout(env, pol, FullComm(), state, Rng(gen, cpu), 50)
    out["eval_rollouts_per_s"] = batch / (time.perf_counter() - t0)

    data = collect(env, pol, 10, 1, torch.Generator().manual_seed(2), cpu)  # 500 states
    sc = CachedScorer(pol, env, data, round_idx=0, version="v1", lam=0.5, objective="paper", cap=5, samples=1,
                      gen=torch.Generator().manual_seed(3), device=cpu)
    space = SearchSpace(feature_quantiles(sc, torch.Generator().manual_seed(0)), 5)
    rng = random.Random(0)
    res = metropolis(lambda: random_rules(space, rng), lambda r: propose(r, space, rng), sc, steps=300, restarts=1,
                     final_fraction=0.0, temperature=0.1, rng=rng)
    progs = [Program((random_rules(space, rng),)) for _ in range(2)]
    t0 = time.perf_counter()
    for p in progs:
        sc.full_score(p)
    full_s = (time.perf_counter() - t0) / len(progs)
    out.update(cached_ms_per_proposal=1000 / res.proposals_per_second, full_s_per_proposal=full_s,
               scorer_speedup=full_s * res.proposals_per_second,
               peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--ns", type=int, nargs="+", default=[10, 20, 40, 80, 160])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--json", default="")
    ap.add_argument("--one", type=int, default=0, help=argparse.SUPPRESS)  # internal: measure one N, print JSON
    a = ap.parse_args()
    if a.one:
        print(json.dumps(measure(a.one, a.threads)))
        return
    rows = []
    print(f"{'N':>4} {'train roll/s':>12} {'agent-steps/s':>13} {'eval roll/s':>11} {'cached ms':>9} "
          f"{'full s':>7} {'ratio':>6} {'peak MB':>8}")
    for n in a.ns:
        cmd = [sys.executable, __file__, "--one", str(n), "--threads", str(a.threads)]
        r = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout.strip().splitlines()[-1])
        rows.append(r)
        print(f"{n:4d} {r['train_rollouts_per_s']:12.2f} {r['train_agent_steps_per_s']:13,.0f} "
              f"{r['eval_rollouts_per_s']:11.2f} {r['cached_ms_per_proposal']:9.1f} {r['full_s_per_proposal']:7.3f} "
              f"{r['scorer_speedup']:6.1f} {r['peak_rss_mb']:8.0f}", flush=True)
    base = rows[0]
    print("cost relative to N = %d (time per rollout or proposal):" % base["n"])
    for r in rows:
        print(f"  N={r['n']:4d}: train x{base['train_rollouts_per_s'] / r['train_rollouts_per_s']:6.1f}  "
              f"eval x{base['eval_rollouts_per_s'] / r['eval_rollouts_per_s']:6.1f}  "
              f"cached scorer x{r['cached_ms_per_proposal'] / base['cached_ms_per_proposal']:6.1f}  "
              f"full scorer x{r['full_s_per_proposal'] / base['full_s_per_proposal']:6.1f}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"threads": a.threads, "rows": rows}, f, indent=2)


if __name__ == "__main__":
    main()
