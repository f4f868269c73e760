"""Training rollouts/s with the step eager (compile=off) against compiled (compile=on), ratios measured in one
process, and the losses of both over the same optimizer steps (issue 39; docs/performance.md, 'The compiled step').

    python benchmarks/bench_compile.py                          # random-cross, B = 50, T = 200, threads 1 and 2
    python benchmarks/bench_compile.py --batch 10 --horizon 20 --steps 5      # a quick look
    python benchmarks/bench_compile.py --device cuda            # B = 50 ... 4096: eager, compiled, captured

One optimizer step = the task's reset of `batch` episodes (buckets of equal N), a rollout of each bucket with
gradients, backward, Adam, as in training.fit. Both modes start from the same weights and generators, so their
losses agree up to the compiled kernels' float rounding (dropout draws from torch's own stream in both). On a GPU,
`captured` is the compiled step in mode="reduce-overhead" (CUDA graphs per shape); without a GPU, --device cuda
stops with one line.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import neurosym_cli  # noqa: F401  (pins the CPU kernels before torch loads)
import torch

from neurosym_cli import step as stepmod
from neurosym_cli.config import ModelConfig
from neurosym_cli.policy import CommTransformer, FullComm
from neurosym_cli.rollout import rollout
from neurosym_cli.tasks import Rng, make_task
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.utils import compiling


def train(env, mode: str, *, batch: int, horizon: int, steps: int, device: torch.device, options: dict | None = None
          ) -> dict:
    """``steps`` optimizer steps under compile=mode -> losses per step, seconds of the first step (compilation
    included) and rollouts/s over the others."""
    compiling.configure("on" if mode != "eager" else "off", device.type)
    stepmod.reset_compiled()
    stepmod.OPTIONS.clear()
    stepmod.OPTIONS.update(options or {"dynamic": False})
    torch.manual_seed(0)
    policy = CommTransformer.for_task(env, ModelConfig()).to(device)
    opt = torch.optim.Adam(policy.parameters(), 1e-3)
    gen = torch.Generator().manual_seed(1)
    rng = Rng(gen, device)
    losses, times = [], []
    for _ in range(steps):
        t0 = time.perf_counter()
        total = 0.0
        for bucket in env.reset(batch, gen):
            traj = rollout(env, policy, FullComm(), bucket.to(device), rng, horizon, stats=False)
            loss = traj.cost.sum() / (batch * horizon)
            loss.backward()
            total += float(loss.detach())
        opt.step()
        opt.zero_grad(set_to_none=True)
        if device.type == "cuda":
            torch.cuda.synchronize()
        losses.append(total)
        times.append(time.perf_counter() - t0)
    rest = times[1:] or times
    return {"mode": mode, "losses": losses, "first_s": times[0], "rollouts_per_s": batch * len(rest) / sum(rest),
            "compile": compiling.record()}


def agreement(a: list[float], b: list[float]) -> float:
    """The largest relative difference between two loss curves."""
    return max(abs(x - y) / max(abs(x), 1e-12) for x, y in zip(a, b))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=50)
    ap.add_argument("--horizon", type=int, default=200)
    ap.add_argument("--steps", type=int, default=20, help="optimizer steps per mode (losses compared over them)")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--device", default="cpu", choices=["cpu", "cuda"])
    ap.add_argument("--batches", default="50,256,1024,4096", help="--device cuda: the batch sizes")
    ap.add_argument("--modes", default="eager,compiled,captured", help="--device cuda: the modes (eager first)")
    ap.add_argument("--json", default="", help="also write the rows here")
    args = ap.parse_args()
    env = make_task(CrossConfig(name="random-cross"), horizon=args.horizon)
    rows = []
    if args.device == "cuda":
        if not torch.cuda.is_available():
            sys.exit("bench_compile: --device cuda needs a GPU, and torch sees none (run the CPU part without it)")
        torch.backends.cuda.matmul.allow_tf32 = False  # TF32 off: the numbers of the CPU's float32
        torch.backends.cudnn.allow_tf32 = False
        dev = torch.device("cuda")
        for b in (int(x) for x in args.batches.split(",")):
            modes = {"eager": None, "compiled": {"dynamic": False},
                     "captured": {"dynamic": False, "mode": "reduce-overhead"}}
            runs = [train(env, m, batch=b, horizon=args.horizon, steps=args.steps, device=dev, options=modes[m])
                    for m in args.modes.split(",")]
            for r in runs:
                rows.append({"device": "cuda", "batch": b, **{k: r[k] for k in ("mode", "rollouts_per_s", "first_s")},
                             "vs_eager": r["rollouts_per_s"] / runs[0]["rollouts_per_s"],
                             "loss_rel_diff": agreement(runs[0]["losses"], r["losses"]),
                             "in_effect": r["compile"]["in_effect"], "why_off": r["compile"]["why_off"]})
                print(json.dumps(rows[-1]), flush=True)
    else:
        dev = torch.device("cpu")
        for th in (int(x) for x in args.threads.split(",")):
            torch.set_num_threads(th)
            eager = train(env, "eager", batch=args.batch, horizon=args.horizon, steps=args.steps, device=dev)
            comp = train(env, "compiled", batch=args.batch, horizon=args.horizon, steps=args.steps, device=dev)
            rows.append({"device": "cpu", "threads": th, "batch": args.batch, "horizon": args.horizon,
                         "eager_rollouts_per_s": eager["rollouts_per_s"],
                         "compiled_rollouts_per_s": comp["rollouts_per_s"],
                         "ratio": comp["rollouts_per_s"] / eager["rollouts_per_s"],
                         "compile_s": comp["compile"]["compile_seconds"], "first_step_s": comp["first_s"],
                         "compiled_in_effect": comp["compile"]["in_effect"],
                         "loss_rel_diff": agreement(eager["losses"], comp["losses"])})
            print(json.dumps(rows[-1]), flush=True)
    if args.json:
        from pathlib import Path

        from neurosym_cli.utils.io import write_json

        write_json(Path(args.json), rows)


if __name__ == "__main__":
    main()
