"""Swarm scaling: time per evaluation step, per training rollout, and peak memory against N, under a program (prog),
the k nearest (dist) and everybody (tf-full), on the swarm task (tasks/swarm.py), each point in its own process.

    python benchmarks/bench_swarm.py                         # N = 10 ... 10,000, the table of docs/performance.md 15
    python benchmarks/bench_swarm.py --sizes 100,1000 --eval-steps 5 --train-steps 10

Evaluation: forward-only steps of one episode (B = 1), the mean over ``--eval-steps`` after a warm-up step, and the
program's filter scan timed on its own (decision time per agent), by the fused kernel and by the torch reference
alternately in the same process (``--scan`` picks the one the steps and rollouts run). Training: one batched BPTT rollout of
``--train-steps`` steps (B = ``--batch``) with its backward pass, the time scaled to a 200-step rollout (linear in
T). Peak memory: the process's maximum resident set (ru_maxrss), model and interpreter included, as measured; the
estimate of policy/footprint.py beside it. A point whose estimate exceeds ``--memory-gb`` is not run: the table
says so and names the largest N that fits. The growth exponent is the slope of log time against log N from 100
agents on (least squares). The model is untrained (timing does not depend on the weights); the program is a
two-rule one of the shape synthesis finds (the nearest agent ahead, and a random one at least 3.6 away).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import time

PROGRAM = "argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nrandom(filter(d >= 3.6, l))"
BASELINES = ("prog", "dist", "tf-full")
DENSE = ("tf-full", "hard-attn")
"""the baselines on the dense path: hard-attn's top-k reads every logit, so its footprint is tf-full's"""
SCAN = "fused"
"""the filter scan a point runs (``--scan``): fused (policy/scan_kernels.py, the default) or reference (torch)"""


def _setup(baseline: str, n: int):
    import neurosym_cli  # noqa: F401  (pins the CPU kernels before torch)
    import torch

    from neurosym_cli.config import ModelConfig
    from neurosym_cli.dsl.parser import parse
    from neurosym_cli.policy.comm import FullComm, NearestComm, ProgramComm, TopKComm
    from neurosym_cli.policy.transformer import CommTransformer
    from neurosym_cli.tasks.swarm import SwarmConfig, SwarmTask

    env = SwarmTask(SwarmConfig(name="swarm", agents_per_group=max(n // 2, 2)))
    torch.manual_seed(0)
    policy = CommTransformer.for_task(env, ModelConfig())
    comm = {"prog": lambda: ProgramComm(parse(PROGRAM), env.features("v1")), "dist": lambda: NearestComm(2),
            "tf-full": FullComm, "hard-attn": lambda: TopKComm(2)}[baseline]()
    return env, policy, comm


def one(baseline: str, n: int, mode: str, steps: int, batch: int) -> dict:
    """One point, in this process: {'seconds': per step (eval) or per 200-step rollout (train), ...}."""
    import torch

    from neurosym_cli.policy.comm import CommBase, CommContext
    from neurosym_cli.rollout import rollout
    from neurosym_cli.tasks.base import Rng

    from neurosym_cli.policy import scan

    torch.set_num_threads(1)
    scan.FUSED = SCAN == "fused"
    env, policy, comm = _setup(baseline, n)
    gen = torch.Generator().manual_seed(0)
    out: dict = {}
    if mode == "eval":
        state = env.reset(1, gen)[0]
        rng = Rng([torch.Generator().manual_seed(1)])
        policy.eval()
        with torch.no_grad():
            rollout(env, policy, comm, state, rng, 1)  # warm-up (kernels compiled, caches built)
            t0 = time.perf_counter()
            rollout(env, policy, comm, state, rng, steps)
            out["seconds"] = (time.perf_counter() - t0) / steps
            if baseline == "prog":  # the filter scan on its own: the program's decision for every agent
                obs = env.observe(state, rng)
                ctx = CommContext(env, state, obs, rng)
                from neurosym_cli.policy import scan

                chosen = scan.FUSED
                for key, fused in (("decision_us_per_agent", chosen), ("decision_ref_us_per_agent", False),
                                   ("decision_us_per_agent", chosen)):  # alternating: the same load for both
                    scan.FUSED = fused
                    t0 = time.perf_counter()
                    for _ in range(3):
                        comm.picks(ctx, 0)
                    t = (time.perf_counter() - t0) / 3 / n * 1e6
                    out[key] = min(out.get(key, t), t)
                scan.FUSED = chosen
                # everything but the scan: the same steps under the picks computed once (a fixed rule)
                fixed = [comm.picks(ctx, 0)]

                class Fixed(CommBase):
                    name = "fixed"

                    def select(self, ctx, logits, r):
                        raise AssertionError("the sparse path asks for picks")

                    def picks(self, ctx, r):
                        return fixed[0]

                t0 = time.perf_counter()
                rollout(env, policy, Fixed(), state, rng, steps)
                out["rest_seconds"] = (time.perf_counter() - t0) / steps
    else:
        state = env.reset(batch, gen)[0]
        rng = Rng(gen)
        policy.train()
        warm = rollout(env, policy, comm, state, rng, 1, stats=False)  # kernels loaded, caches built
        warm.cost.sum().backward()
        policy.zero_grad(set_to_none=True)
        t0 = time.perf_counter()
        traj = rollout(env, policy, comm, state, rng, steps, stats=False)
        traj.cost.sum().backward()
        out["seconds"] = (time.perf_counter() - t0) * 200 / steps  # per 200-step rollout of the batch
    out["peak_gb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20  # KiB -> GiB
    return out


def estimate_gb(baseline: str, n: int, mode: str, steps: int, batch: int) -> float:
    from neurosym_cli.config import ModelConfig
    from neurosym_cli.policy.footprint import estimate_bytes
    from neurosym_cli.tasks.swarm import SwarmConfig

    cfg = SwarmConfig(name="swarm")
    return estimate_bytes(n, batch=1 if mode == "eval" else batch, horizon=steps if mode == "train" else 1, rounds=1,
                          model=ModelConfig(), k=2, dense=baseline in DENSE, training=mode == "train",
                          sparse_from=cfg.sparse_from) / 2 ** 30


def slope(points: list[tuple[int, float]]) -> float:
    """Least-squares slope of log y against log N."""
    xs, ys = [math.log(n) for n, _ in points], [math.log(y) for _, y in points]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / max(sum((x - mx) ** 2 for x in xs), 1e-12)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="10,100,1000,3000,10000")
    ap.add_argument("--baselines", default=",".join(BASELINES))
    ap.add_argument("--eval-steps", type=int, default=3)
    ap.add_argument("--train-steps", type=int, default=10)
    ap.add_argument("--batch", type=int, default=1)
    ap.add_argument("--memory-gb", type=float, default=16.0, help="skip points whose estimate exceeds this")
    ap.add_argument("--modes", default="eval,train")
    ap.add_argument("--scan", choices=("fused", "reference"), default="fused",
                    help="the program's filter scan: the fused kernel (default) or the torch reference")
    ap.add_argument("--table", help="print the tables of the JSON rows a previous run printed (one per line)")
    ap.add_argument("--one", nargs=3, metavar=("BASELINE", "N", "MODE"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    global SCAN
    SCAN = args.scan
    if args.one:
        b, n, mode = args.one[0], int(args.one[1]), args.one[2]
        steps = args.eval_steps if mode == "eval" else args.train_steps
        print(json.dumps(one(b, n, mode, steps, args.batch)))
        return
    if args.table:
        with open(args.table) as f:
            rows = [json.loads(ln) for ln in f if ln.startswith("{")]
        return tables(rows)
    sizes = [int(s) for s in args.sizes.split(",")]
    rows = []
    for mode in args.modes.split(","):
        steps = args.eval_steps if mode == "eval" else args.train_steps
        for b in args.baselines.split(","):
            for n in sizes:
                est = estimate_gb(b, n, mode, steps if mode == "train" else 1, args.batch)
                row = {"mode": mode, "baseline": b, "n": n, "estimate_gb": est}
                if est > args.memory_gb:
                    row["skipped"] = f"estimate {est:.1f} GB > {args.memory_gb:g} GB"
                else:
                    cmd = [sys.executable, __file__, "--one", b, str(n), mode, "--eval-steps", str(args.eval_steps),
                           "--train-steps", str(args.train_steps), "--batch", str(args.batch), "--scan", args.scan]
                    r = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, "OMP_NUM_THREADS": "1"})
                    if r.returncode != 0:
                        row["skipped"] = f"failed: {(r.stderr.strip().splitlines() or ['?'])[-1][:120]}"
                    else:
                        row.update(json.loads(r.stdout.strip().splitlines()[-1]))
                rows.append(row)
                print(json.dumps(row), flush=True)
    tables(rows)


def tables(rows: list[dict]) -> None:
    """The markdown tables of docs/performance.md section 15 from the measured rows."""
    sizes = sorted({r["n"] for r in rows})
    modes = list(dict.fromkeys(r["mode"] for r in rows))
    baselines = list(dict.fromkeys(r["baseline"] for r in rows))
    print()
    unit = {"eval": "s/step", "train": "s per 200-step rollout"}
    for mode in modes:
        print(f"| {mode} ({unit[mode]}) | " + " | ".join(f"N = {n:,}" for n in sizes) + " | exponent (N >= 100) |")
        print("|---|" + "---:|" * (len(sizes) + 1))
        for b in baselines:
            cells, pts = [], []
            for n in sizes:
                r = next((r for r in rows if r["mode"] == mode and r["baseline"] == b and r["n"] == n), None)
                if r is None:
                    cells.append("-")
                elif "seconds" in r:
                    cells.append(f"{r['seconds']:.3g} s, {r['peak_gb']:.2f} GB (est. {r['estimate_gb']:.2f})")
                    if n >= 100:
                        pts.append((n, r["seconds"]))
                else:
                    cells.append(f"does not fit: {r['skipped']}")
            exp = f"{slope(pts):.2f}" if len(pts) >= 2 else "-"
            print(f"| {b} | " + " | ".join(cells) + f" | {exp} |")
        print()
    dec = [r for r in rows if "decision_us_per_agent" in r]
    if dec:
        print("| prog evaluation step | " + " | ".join(f"N = {r['n']:,}" for r in dec) + " | exponent (N >= 100) |")
        print("|---|" + "---:|" * (len(dec) + 1))
        scan = [(r["n"], r["decision_us_per_agent"] * r["n"] / 1e6) for r in dec]
        rest = [(r["n"], r["rest_seconds"]) for r in dec if "rest_seconds" in r]
        for name, pts in (("filter scan (s)", scan), ("everything else (s)", rest)):
            fit = [p for p in pts if p[0] >= 100]
            exp = f"{slope(fit):.2f}" if len(fit) >= 2 else "-"
            print(f"| {name} | " + " | ".join(f"{v:.3g}" for _, v in pts) + f" | {exp} |")
        print("| decision per agent (us) | " + " | ".join(f"{r['decision_us_per_agent']:.1f}" for r in dec) + " | |")
        if all("decision_ref_us_per_agent" in r for r in dec):
            print("| decision per agent, torch reference scan (us) | "
                  + " | ".join(f"{r['decision_ref_us_per_agent']:.1f}" for r in dec) + " | |")


if __name__ == "__main__":
    main()
