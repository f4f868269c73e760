"""Speed of MCMC program scoring: the cached incremental scorer vs a full-forward (reference-style) scorer.

    python benchmarks/bench_synth.py                         # paper-size random-cross dataset (300 rollouts)
    python benchmarks/bench_synth.py --rollouts 30 --steps 300   # a quick look

Both scorers run in the same process on the same dataset D (oracle rollouts; the weights do not change the
cost) and the same programs. Prints the dataset size, proposals/s of a real MCMC run with the cached scorer (by
default with each back-end, numba and torch, on the same search), seconds per proposal of the full forward
pass, their ratio, and the projected time of 10k MCMC steps.
"""

from __future__ import annotations

import argparse
import json
import random
import time

import torch

from neurosym_cli.config import ModelConfig
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.dsl.ast import Program
from neurosym_cli.dsl.sampling import SearchSpace, propose, random_rules
from neurosym_cli.tasks import make_task
from neurosym_cli.policy import CommTransformer
from neurosym_cli.synth.dataset import collect
from neurosym_cli.synth.mcmc import metropolis
from neurosym_cli.synth.objective import CachedScorer
from neurosym_cli.synth.search import feature_quantiles


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rollouts", type=int, default=300)
    ap.add_argument("--stride", type=int, default=1, help="1 = every step; the CLI default is synth.stride=10")
    ap.add_argument("--rules", type=int, default=5)
    ap.add_argument("--steps", type=int, default=2000, help="MCMC steps timed with the cached scorer")
    ap.add_argument("--full", type=int, default=3, help="proposals timed with the full-forward scorer")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--backend", default="both", choices=["both", "numba", "torch", "auto"],
                    help="cached scorer back-end(s) to time; both = numba and torch side by side")
    ap.add_argument("--json", default="")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    dev = torch.device(a.device)
    env = make_task(CrossConfig(name="random-cross"))
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig()).to(dev).eval()
    t0 = time.perf_counter()
    data = collect(env, pol, a.rollouts, a.stride, torch.Generator().manual_seed(0), dev)
    states = sum(b.states for b in data)
    pairs = sum(b.states * b.n_agents ** 2 for b in data)
    print(f"dataset: {a.rollouts} rollouts, stride {a.stride}: {states} states, {pairs / 1e6:.1f}M agent pairs "
          f"(collected in {time.perf_counter() - t0:.0f} s)")
    rates, setups, rows = {}, {}, {}
    backends = ["numba", "torch"] if a.backend == "both" else [a.backend]
    for backend in backends:  # the same search (seed, programs) with each back-end of the cached scorer
        t0 = time.perf_counter()
        sc = CachedScorer(pol, env, data, round_idx=0, version="v1", lam=0.5, objective="paper", cap=a.rules, samples=1,
                          gen=torch.Generator().manual_seed(1), device=dev, backend=backend)
        space = SearchSpace(feature_quantiles(sc, torch.Generator().manual_seed(0)), a.rules)
        setups[backend] = time.perf_counter() - t0
        rng = random.Random(0)
        res = metropolis(lambda: random_rules(space, rng), lambda r: propose(r, space, rng), sc, steps=a.steps,
                         restarts=1, final_fraction=0.0, temperature=0.1, rng=rng)
        rates[backend] = res.proposals_per_second
        rows[backend] = sc.rows_recomputed / a.steps
        print(f"cached scorer ({backend:5s}): {rates[backend]:8.1f} proposals/s  ({1000 / rates[backend]:.1f} ms each; "
              f"set-up {setups[backend]:.1f} s); agents recomputed per proposal: {rows[backend] / 1e3:.1f}k of "
              f"{sum(b.states * b.n_agents for b in data) / 1e3:.0f}k; best objective {res.best_score.total:.4f}")
    progs = [Program((random_rules(space, rng),)) for _ in range(a.full)]
    t0 = time.perf_counter()
    for p in progs:
        sc.full_score(p)
    full_s = (time.perf_counter() - t0) / a.full
    print(f"full-forward scorer:         {full_s:8.2f} s per proposal "
          f"({full_s / (pairs / 1e6):.2f} s per million pairs)")
    for backend, rate in rates.items():
        print(f"speed-up ({backend}): {full_s * rate:.0f}x;  10k MCMC steps: cached {1e4 / rate / 60:.1f} min "
              f"(+{setups[backend]:.0f} s set-up), full-forward {1e4 * full_s / 3600:.1f} h")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"rollouts": a.rollouts, "stride": a.stride, "states": states, "pairs": pairs,
                       "setup_s": setups, "cached_proposals_per_s": rates, "rows_recomputed_per_proposal": rows,
                       "full_s_per_proposal": full_s, "speedup": {b: full_s * r for b, r in rates.items()},
                       "threads": a.threads, "device": a.device}, f, indent=2)


if __name__ == "__main__":
    main()
