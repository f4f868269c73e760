"""Speed of the batched simulator and of batched BPTT training vs a reference-style loop, side by side.

    python benchmarks/bench_train.py                      # throughput figures (a few minutes)
    python benchmarks/bench_train.py --learn 1000         # plus: equal-rollout learning comparison
    python benchmarks/bench_train.py --learn 10000 --threads 2   # the paper budget (the reference loop takes ~1 h)

Prints (1) env steps/s of the simulator vs batch size, (2) training rollouts/s on random-cross at paper size
(T = 200, 10-40 agents) for the batched loop vs the reference-style loop (one rollout per Adam step, lr 1e-3,
same model), measured in the same process, and their ratio; (3) with --learn R, the evaluation loss (20 seeds)
of both loops after R rollouts each, and their wall times.
"""

from __future__ import annotations

import argparse
import json
import time

import torch

from neurosym_cli.config import ModelConfig, OptimConfig
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.tasks import Rng, make_task
from neurosym_cli.evaluation import evaluate, summarize
from neurosym_cli.policy import CommTransformer, FullComm
from neurosym_cli.training import FitSpec, fit

CROSS = CrossConfig(name="random-cross", test_settings=["0", "1", "0-2", "0-1", "0-1-2", "0-1-2-3"])


class Quiet:
    def update(self, step, total, metrics):
        pass


def env_steps_per_second(batch: int, steps: int = 50) -> float:
    """Episode-steps per second of reset + observe + step + cost with random actions (no policy, no grad)."""
    env = make_task(CROSS)
    g = torch.Generator().manual_seed(0)
    buckets = [b.to(DEVICE) for b in env.reset(batch, g)]
    rng = Rng(g, DEVICE)
    t0 = time.perf_counter()
    with torch.no_grad():
        for s in buckets:
            for _ in range(steps):
                env.observe(s, rng)
                a = rng.randn(s.batch, s.n_agents, 2)
                s = env.step(s, a)
                env.cost(s, a)
    if DEVICE.type == "cuda":
        torch.cuda.synchronize()
    return batch * steps / (time.perf_counter() - t0)


DEVICE = torch.device("cpu")


def train_rate(batch: int, rollouts: int, lr: float, lr_final: float, clip: float) -> tuple[float, CommTransformer]:
    torch.manual_seed(0)
    env = make_task(CROSS)
    pol = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig()).to(DEVICE)
    spec = FitSpec(rollouts=rollouts, batch=batch, horizon=env.horizon, checkpoint_every=10**9,
                   optim=OptimConfig(lr=lr, lr_final=lr_final, grad_clip=clip, step_per_bucket=True))  # with one rollout per step: one bucket
    t0 = time.perf_counter()
    fit(pol, env, FullComm(), spec, gen=torch.Generator().manual_seed(0), device=DEVICE,
        reporter=Quiet(), save=lambda s: None)
    if DEVICE.type == "cuda":
        torch.cuda.synchronize()
    return rollouts / (time.perf_counter() - t0), pol


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--batch", type=int, default=50, help="rollouts per step of the batched loop")
    ap.add_argument("--learn", type=int, default=0, help="rollout budget of the learning comparison (0 = skip)")
    ap.add_argument("--only", choices=["reference", "batched"], default=None, help="run one side of --learn only")
    ap.add_argument("--skip-speed", action="store_true", help="skip the throughput figures")
    ap.add_argument("--device", default="cpu", help="cpu or cuda")
    ap.add_argument("--json", default="", help="also write the figures to this file")
    args = ap.parse_args()
    global DEVICE
    DEVICE = torch.device(args.device)
    torch.set_num_threads(args.threads)
    out: dict = {"threads": args.threads, "torch": torch.__version__, "device": args.device}

    if not args.skip_speed:
        speed(args, out)
    if args.learn:
        learn(args, out)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=2)


def speed(args, out: dict) -> None:
    print("== simulator: episode-steps/s vs batch (random-cross, 10-40 agents, no policy)")
    out["env_steps_per_s"] = {}
    for b in (1, 10, 100, 1000, 10000):
        r = env_steps_per_second(b)
        out["env_steps_per_s"][b] = r
        print(f"  batch {b:5d}: {r:12,.0f} episode-steps/s")

    print(f"== training throughput at paper size (T=200): batched ({args.batch}/step) vs one rollout per step")
    ref_rate, _ = train_rate(1, 10, 1e-3, 1e-3, 1e9)
    bat_rate, _ = train_rate(args.batch, 4 * args.batch, 1e-2, 2e-4, 1.0)
    out.update(reference_rollouts_per_s=ref_rate, batched_rollouts_per_s=bat_rate, speedup=bat_rate / ref_rate)
    print(f"  reference-style loop: {ref_rate:6.2f} rollouts/s  -> 10k rollouts in {1e4 / ref_rate / 60:5.1f} min")
    print(f"  batched loop:         {bat_rate:6.2f} rollouts/s  -> 10k rollouts in {1e4 / bat_rate / 60:5.1f} min")
    print(f"  speed-up: {bat_rate / ref_rate:.1f}x")



def learn(args, out: dict) -> None:
    print(f"== learning: {args.learn} rollouts each, eval loss over 20 seeds (tf-full)")
    env = make_task(CROSS)
    # reference: one rollout per Adam step, lr 1e-3, no clipping (reference-implementation.md section 3.1);
    # batched: the defaults of conf/ (optim.lr 1e-2 -> 2e-4 cosine, clip 1.0, one Adam step per bucket)
    loops = {"reference": (1, 1e-3, 1e-3, 1e9), "batched": (args.batch, 1e-2, 2e-4, 1.0)}
    for name, (b, lr, lrf, clip) in loops.items():
        if args.only and name != args.only:
            continue
        t0 = time.perf_counter()
        _, pol = train_rate(b, args.learn, lr, lrf, clip)
        wall = time.perf_counter() - t0
        s = summarize(evaluate(env, pol, FullComm(), range(20), DEVICE))["cost"]
        out[f"learn_{name}"] = {"rollouts": args.learn, "wall_s": wall, "eval_loss": s["mean"], "std": s["std"]}
        print(f"  {name:9s}: eval loss {s['mean']:8.2f} ± {s['std']:.2f}   wall {wall / 60:6.1f} min", flush=True)


if __name__ == "__main__":
    main()
