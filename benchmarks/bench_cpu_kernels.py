"""What the default CPU-kernel pin (cpu_kernels=avx2, utils/cpu.py) costs: training steps and synthesis scoring with
and without it, alternating in one run, each measurement in a fresh process (the pin must hold before torch loads).

    nice -n 5 python benchmarks/bench_cpu_kernels.py                 # 6 rounds, random-cross (a few minutes)
    python benchmarks/bench_cpu_kernels.py --rounds 2 --steps 3 --json /tmp/k.json   # a quick look

Round r runs one process per mode, avx2 then native on even rounds and the other way on odd ones, so a change of
load on the machine hits both alike. Each process: BPTT training steps of the oracle on random-cross (full soft
attention: seconds per optimizer step, median over the steps after the first), then the synthesis dataset D
(seconds: oracle rollouts without gradients) and an MCMC search scored on it (seconds per proposal, the default
scorer). Each figure in CPU time of the process (one thread: the work itself, little moved by other jobs on a
shared machine) and in wall time. Prints
the ratio pinned / native of each figure per round, its median and range (>1: the pin is slower), and whether
both modes trained bit-identical weights (on an AVX2 CPU they do: native is AVX2 there, only MKL_CBWR differs).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

MODES = ("avx2", "native")


def child(a: argparse.Namespace) -> None:
    """One measurement in this process, in the mode of NEUROSYM_CPU_KERNELS (applied by importing neurosym_cli)."""
    import hashlib
    import random
    import time

    import neurosym_cli  # noqa: F401  (first: applies the mode before torch loads)
    import torch

    from neurosym_cli.config import ModelConfig, OptimConfig
    from neurosym_cli.dsl.sampling import SearchSpace, propose, random_rules
    from neurosym_cli.policy import CommTransformer, FullComm
    from neurosym_cli.synth.dataset import collect
    from neurosym_cli.synth.mcmc import metropolis
    from neurosym_cli.synth.objective import CachedScorer
    from neurosym_cli.synth.search import feature_quantiles
    from neurosym_cli.tasks.random_cross import CrossConfig
    from neurosym_cli.tasks.registry import make_task
    from neurosym_cli.training import FitSpec, fit
    from neurosym_cli.utils.cpu import runtime

    torch.set_num_threads(a.threads)
    env = make_task(CrossConfig(name="random-cross"), a.horizon)
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, env.rounds, ModelConfig(), pair_dim=env.pair_dim)
    stamps: list[tuple[float, float]] = []  # (wall, CPU) seconds at the end of each optimizer step

    class Clock:
        def update(self, step, total, metrics):
            stamps.append((time.perf_counter(), time.process_time()))

    spec = FitSpec(rollouts=a.batch * (a.steps + 1), batch=a.batch, horizon=a.horizon, checkpoint_every=10**9,
                   optim=OptimConfig(step_per_bucket=False))
    fit(pol, env, FullComm(), spec, gen=torch.Generator().manual_seed(0), device=torch.device("cpu"), reporter=Clock(),
        save=lambda s: None)
    # the first step warms up (allocations, caches), so the steps timed run from its end
    wall = [b[0] - a_[0] for a_, b in zip(stamps, stamps[1:])]
    cpu_s = [b[1] - a_[1] for a_, b in zip(stamps, stamps[1:])]
    weights = hashlib.sha256(b"".join(p.detach().numpy().tobytes() for p in pol.parameters())).hexdigest()[:16]

    pol.eval()
    t0, c0 = time.perf_counter(), time.process_time()
    data = collect(env, pol, a.rollouts, 10, torch.Generator().manual_seed(0), torch.device("cpu"))
    collect_s, collect_cpu = time.perf_counter() - t0, time.process_time() - c0
    sc = CachedScorer(pol, env, data, round_idx=0, version="v1", lam=0.5, objective="paper", cap=5, samples=1,
                      gen=torch.Generator().manual_seed(1), device=torch.device("cpu"), backend="auto")
    space = SearchSpace(feature_quantiles(sc, torch.Generator().manual_seed(0)), 5)
    rng = random.Random(0)
    c0 = time.process_time()
    res = metropolis(lambda: random_rules(space, rng), lambda r: propose(r, space, rng), sc, steps=a.mcmc, restarts=1,
                     final_fraction=0.0, temperature=0.1, rng=rng)
    mcmc_cpu = time.process_time() - c0
    print(json.dumps({"runtime": runtime(), "step_s": statistics.median(wall), "step_cpu": statistics.median(cpu_s),
                      "steps": len(wall), "collect_s": collect_s, "collect_cpu": collect_cpu,
                      "proposals_per_s": res.proposals_per_second, "proposal_cpu": mcmc_cpu / a.mcmc,
                      "weights": weights, "objective": res.best_score.total}))


def measure(mode: str, a: argparse.Namespace) -> dict:
    """One child process in ``mode``, from an environment without the pin's variables (as a fresh shell)."""
    pin = ("ATEN_CPU_CAPABILITY", "MKL_CBWR", "ONEDNN_MAX_CPU_ISA")
    env = {k: v for k, v in os.environ.items() if k not in pin}
    env["NEUROSYM_CPU_KERNELS"] = mode
    args = [sys.executable, __file__, "--child", *(f"--{k}={v}" for k, v in vars(a).items()
                                                    if k not in ("child", "json", "rounds"))]
    p = subprocess.run(args, env=env, capture_output=True, text=True)
    if p.returncode != 0:
        last = (p.stderr.strip().splitlines() or ["(no output)"])[-1]
        raise SystemExit(f"bench_cpu_kernels: the {mode} process failed (exit {p.returncode}): {last}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def spread(xs: list[float]) -> str:
    return f"median {statistics.median(xs):.3f}, range {min(xs):.3f}-{max(xs):.3f} over {len(xs)} rounds"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=6, help="pairs of processes (one per mode)")
    ap.add_argument("--threads", type=int, default=1, help="torch threads of each process")
    ap.add_argument("--batch", type=int, default=10, help="rollouts per training step")
    ap.add_argument("--horizon", type=int, default=100, help="steps per episode")
    ap.add_argument("--steps", type=int, default=6, help="training steps timed (after one warm-up step)")
    ap.add_argument("--rollouts", type=int, default=30, help="rollouts of the synthesis dataset (stride 10)")
    ap.add_argument("--mcmc", type=int, default=300, help="MCMC proposals timed")
    ap.add_argument("--json", default="", help="also write every measurement and the ratios here")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(a)
        return
    runs: list[dict[str, dict]] = []
    for r in range(a.rounds):
        row = {}
        for mode in (MODES if r % 2 == 0 else MODES[::-1]):
            row[mode] = m = measure(mode, a)
            m["proposal_s"] = 1 / m["proposals_per_s"]
            print(f"round {r + 1}/{a.rounds} {mode:6s}: step {m['step_cpu'] * 1e3:6.0f} ms CPU ({m['step_s'] * 1e3:6.0f}"
                  f" wall), dataset {m['collect_cpu']:5.2f} s CPU ({m['collect_s']:5.2f} wall), proposal "
                  f"{m['proposal_cpu'] * 1e3:5.1f} ms CPU ({1e3 / m['proposals_per_s']:5.1f} wall); torch "
                  f"{m['runtime']['capability']}, MKL_CBWR={m['runtime']['mkl_cbwr']}", flush=True)
        runs.append(row)
    ratio = {f"{what} ({clock})": [x["avx2"][key] / x["native"][key] for x in runs]
             for what, keys in (("training step", ("step_cpu", "step_s")), ("dataset collection", ("collect_cpu",
                                "collect_s")), ("MCMC proposal", ("proposal_cpu", "proposal_s")))
             for clock, key in zip(("CPU", "wall"), keys)}
    rt = runs[0]["native"]["runtime"]
    print(f"\ntime pinned / native, per round (CPU time: what the work costs; wall: with the machine's load)")
    print(f"{rt['cpu']} ({rt['machine']}, avx512f {rt['avx512f']}), torch {rt['torch']}, {a.threads} thread(s); "
          f"native runs torch's {rt['capability']} kernels")
    for name, xs in ratio.items():
        print(f"  {name:26s}: {spread(xs)}")
    same = {x["avx2"]["weights"] == x["native"]["weights"] for x in runs}
    print("trained weights: " + ("bit-identical in both modes" if same == {True} else "differ between the modes")
          + f"; best objective {runs[0]['avx2']['objective']:.6f} (avx2) vs {runs[0]['native']['objective']:.6f}"
          " (native)")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"args": vars(a), "runs": runs, "ratios": ratio}, f, indent=2)


if __name__ == "__main__":
    main()
