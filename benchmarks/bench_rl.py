"""Training cost of the rl baseline (paper appendix D: communication decisions as actions, policy gradient) next to
the oracle's BPTT, one step of each alternating in one process, so load on the machine hits both alike.

    python benchmarks/bench_rl.py                       # random-cross, paper sizes (13 episodes, T = 200)
    python benchmarks/bench_rl.py --episodes 4 --horizon 20 --repeats 2   # a quick look

One training step = a rollout of ``episodes`` episodes with gradients, the loss, backward, as in ``training.fit``.
BPTT: the oracle's (full soft attention). rl: the same transformer with a Bernoulli gate per pair, plus the
score-function term of its decisions (policy/gated.py). Prints seconds per step, rollouts per second and the ratio.
"""

from __future__ import annotations

import argparse
import json
import time

import torch

from neurosym_cli.commands.apps import compose_config
from neurosym_cli.config import ModelConfig
from neurosym_cli.envs import Rng, make_env
from neurosym_cli.policy import make_comm
from neurosym_cli.policy.gated import GatedComm, score_function_loss
from neurosym_cli.policy.transformer import CommTransformer
from neurosym_cli.rollout import rollout


def step(env, pol, comm, bucket, rng, horizon: int, detach: bool) -> float:
    """Seconds of one training step (rollout, loss, backward)."""
    discount = torch.ones(horizon)
    t0 = time.perf_counter()
    traj = rollout(env, pol, comm, bucket, rng, horizon, detach, stats=False)
    loss = traj.cost.sum()
    if traj.logp is not None:
        loss = loss + score_function_loss(traj.cost, traj.comm_degree, traj.logp, discount, 0.1, True)
    loss.backward()
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--task", default="random-cross")
    ap.add_argument("--episodes", type=int, default=13, help="episodes per step (paper budget: 50 cut into ~4)")
    ap.add_argument("--horizon", type=int, default=0, help="0 = the task's")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--json", default="")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    task = compose_config("train", [f"task={a.task}"]).task
    env = make_env(task)
    horizon = a.horizon or task.horizon
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, task.rounds, ModelConfig())
    g = torch.Generator().manual_seed(0)
    rng = Rng(g, torch.device("cpu"))
    bucket = max(env.reset(a.episodes, g), key=lambda b: b.batch)
    comms = {"bptt (oracle, full attention)": make_comm("full", 0), "rl (gate + policy gradient)": GatedComm(task.rounds)}
    times: dict[str, list[float]] = {k: [] for k in comms}
    for r in range(a.repeats + 1):  # the first round is a warm-up
        for name, comm in comms.items():
            s = step(env, pol, comm, bucket, rng, horizon, task.detach_state)
            if r:
                times[name].append(s)
    print(f"{a.task}: the largest bucket of {a.episodes} episodes, {bucket.batch} episodes of {bucket.pos.shape[1]} "
          f"agents, T = {horizon}, {a.threads} thread(s), best of {a.repeats}")
    out = {}
    for name, ts in times.items():
        best = min(ts)
        out[name] = {"seconds_per_step": best, "rollouts_per_second": bucket.batch / best}
        print(f"  {name:<32} {best:7.2f} s per step   {bucket.batch / best:6.2f} rollouts/s")
    names = list(out)
    ratio = out[names[1]]["seconds_per_step"] / out[names[0]]["seconds_per_step"]
    print(f"  rl / bptt time per step: {ratio:.2f}")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump({"task": a.task, "episodes": bucket.batch, "agents": bucket.pos.shape[1], "horizon": horizon, "threads": a.threads,
                       "results": out, "ratio": ratio}, fh, indent=1)


if __name__ == "__main__":
    main()
