"""Does scoring programs on every 10th state (the default `synth.stride=10`) change which program wins?

    python benchmarks/bench_stride.py --oracle outputs/random-cross/paper/seed0/train/oracle/model.pt

Collects the paper-size dataset (300 oracle rollouts) at stride 1 and at stride S (the same rollouts: the
strided states are a subset), runs an MCMC search on the strided data, and re-scores every distinct program it
visited (up to --programs) on both datasets. Prints the rank correlation of the two objectives, the largest
relative difference, the objective on the full data of the program the strided search picked vs the best
visited program, and seconds per proposal of the cached scorer at each stride and of the full-forward scorer on
the full data.
"""

from __future__ import annotations

import argparse
import random
import time

import torch

from pathlib import Path

from neurosym_cli.run.checkpoints import load_checkpoint, policy_from_payload
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.dsl.ast import Program
from neurosym_cli.dsl.sampling import SearchSpace, propose, random_rules
from neurosym_cli.tasks import make_task
from neurosym_cli.synth.dataset import collect
from neurosym_cli.synth.mcmc import metropolis
from neurosym_cli.synth.objective import CachedScorer
from neurosym_cli.synth.search import feature_quantiles


def ranks(x: list[float]) -> list[float]:
    order = sorted(range(len(x)), key=lambda i: x[i])
    r = [0.0] * len(x)
    for k, i in enumerate(order):
        r[i] = float(k)
    return r


def spearman(a: list[float], b: list[float]) -> float:
    ra, rb = ranks(a), ranks(b)
    n = len(a)
    ma, mb = sum(ra) / n, sum(rb) / n
    cov = sum((x - ma) * (y - mb) for x, y in zip(ra, rb))
    va = sum((x - ma) ** 2 for x in ra) ** 0.5
    vb = sum((y - mb) ** 2 for y in rb) ** 0.5
    return cov / (va * vb)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--oracle", required=True)
    ap.add_argument("--rollouts", type=int, default=300)
    ap.add_argument("--stride", type=int, default=10)
    ap.add_argument("--rules", type=int, default=5)
    ap.add_argument("--lam", type=float, default=0.5)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--programs", type=int, default=100)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    cpu = torch.device("cpu")
    pol = policy_from_payload(load_checkpoint(Path(a.oracle), "neurosym train task=random-cross budget=paper")).eval()
    env = make_task(CrossConfig(name="random-cross"))

    def scorer(stride: int) -> CachedScorer:
        data = collect(env, pol, a.rollouts, stride, torch.Generator().manual_seed(0), cpu)
        return CachedScorer(pol, env, data, round_idx=0, version="v1", lam=a.lam, objective="paper", cap=a.rules,
                            samples=1, gen=torch.Generator().manual_seed(1), device=cpu)

    sub, full = scorer(a.stride), scorer(1)
    print(f"stride {a.stride}: {sub.total_states} states; stride 1: {full.total_states} states")
    space = SearchSpace(feature_quantiles(sub, torch.Generator().manual_seed(0)), a.rules)
    visited: list = []

    class Recording:  # the strided scorer, remembering every program the search scores
        def score(self, rules):
            visited.append(rules)
            return sub.score(rules)

        def accept(self):
            sub.accept()

    rng = random.Random(0)
    res = metropolis(lambda: random_rules(space, rng), lambda r: propose(r, space, rng), Recording(), steps=a.steps,
                     restarts=4, final_fraction=0.2, temperature=0.1, rng=rng)
    print(f"MCMC on stride {a.stride}: {a.steps} steps, {1000 / res.proposals_per_second:.1f} ms per proposal")
    seen: dict = {}
    pick = random.Random(1)
    for p in [res.best] + pick.sample(visited, min(a.programs, len(visited))):
        seen.setdefault(p, None)
    progs = list(seen)
    t0 = time.perf_counter()
    sub.current = full.current = None  # score each program from scratch
    on_sub = [sub.score(p).total for p in progs]
    on_full = [full.score(p).total for p in progs]
    full_inc_s = (time.perf_counter() - t0) / len(progs)
    rel = max(abs(x - y) / abs(y) for x, y in zip(on_sub, on_full))
    best_full = min(on_full)
    print(f"{len(progs)} distinct programs: Spearman rank correlation {spearman(on_sub, on_full):.4f}, "
          f"largest relative difference {rel * 100:.2f}%")
    print(f"program picked on stride {a.stride}: objective on the full data {on_full[0]:.4f}; best of the "
          f"visited programs on the full data {best_full:.4f} ({(on_full[0] / best_full - 1) * 100:+.2f}%)")
    t0 = time.perf_counter()
    full.full_score(Program((res.best,)))
    print(f"full data: {time.perf_counter() - t0:.2f} s per full-forward proposal; "
          f"(non-incremental cached scoring of both datasets: {full_inc_s:.2f} s per program)")


if __name__ == "__main__":
    main()
