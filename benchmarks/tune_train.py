"""Learning curves of the batched loop for a few optimiser settings (used to pick the defaults of conf/).

    python benchmarks/tune_train.py --batch 50 --lr 3e-3 --lr-final 3e-4 --rollouts 10000 [--device cuda]
Prints the training loss every ~5% of the budget and the final evaluation loss (20 seeds, tf-full).
"""

from __future__ import annotations

import argparse
import json
import time

import torch

from neurosym_cli.config import ModelConfig, OptimConfig
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.tasks.random_grid import GridConfig
from neurosym_cli.tasks import make_task
from neurosym_cli.evaluation import evaluate, summarize
from neurosym_cli.policy import CommTransformer, FullComm
from neurosym_cli.training import FitSpec, fit

TASKS = {
    "random-cross": CrossConfig(name="random-cross", test_settings=["0", "1", "0-2", "0-1", "0-1-2", "0-1-2-3"]),
    "random-grid": GridConfig(name="random-grid", ell=14.0, test_settings=["rlu", "url", "ull", "rrd"]),
}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--task", default="random-cross", choices=list(TASKS))
    ap.add_argument("--batch", type=int, default=100)
    ap.add_argument("--rollouts", type=int, default=10_000)
    ap.add_argument("--lr", type=float, default=3e-3)
    ap.add_argument("--lr-final", type=float, default=3e-4)
    ap.add_argument("--clip", type=float, default=1.0)
    ap.add_argument("--gamma", type=float, default=1.0)
    ap.add_argument("--step-per-bucket", action="store_true")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--json", default="")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    torch.manual_seed(0)
    dev = torch.device(a.device)
    env = make_task(TASKS[a.task])
    pol = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig()).to(dev)
    spec = FitSpec(rollouts=a.rollouts, batch=a.batch, horizon=env.horizon, checkpoint_every=10**9,
                   optim=OptimConfig(lr=a.lr, lr_final=a.lr_final, grad_clip=a.clip, gamma=a.gamma,
                                     step_per_bucket=a.step_per_bucket))
    tag = f"{a.task} B={a.batch} lr={a.lr}->{a.lr_final} clip={a.clip} gamma={a.gamma} per_bucket={a.step_per_bucket}"
    t0 = time.perf_counter()

    class Rep:
        def update(self, step, total, m):
            if step % max(1, total // 20) == 0 or step == total:
                print(f"[{tag}] {m['rollouts']:6d} rollouts  loss {m['loss']:8.2f}  {time.perf_counter() - t0:5.0f} s",
                      flush=True)

    fit(pol, env, FullComm(), spec, gen=torch.Generator().manual_seed(0), device=dev,
        reporter=Rep(), save=lambda s: None)
    wall = time.perf_counter() - t0
    s = summarize(evaluate(env, pol, FullComm(), range(20), dev))["cost"]
    print(f"[{tag}] FINAL eval loss {s['mean']:.2f} ± {s['std']:.2f}  train wall {wall:.0f} s", flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"tag": tag, "eval_loss": s["mean"], "std": s["std"], "wall_s": wall}, f)


if __name__ == "__main__":
    main()
