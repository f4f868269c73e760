"""Training cost of the rl baseline (paper appendix D: communication decisions as actions, policy gradient) next to
the oracle's BPTT, one step of each alternating in one process, so load on the machine hits both alike.

    python benchmarks/bench_rl.py                       # random-cross, paper sizes (13 episodes, T = 200)
    python benchmarks/bench_rl.py --episodes 4 --horizon 20 --repeats 2   # a quick look
    python benchmarks/bench_rl.py --curves EXP --json docs/results/bench-rl-curves.json \
        --plot docs/figures/rl-time-to-loss.png   # training loss against wall time: oracle BPTT vs rl from scratch
    python benchmarks/bench_rl.py --replot docs/results/bench-rl-curves.json --plot docs/figures/rl-time-to-loss.png

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
from neurosym_cli.tasks import Rng, make_task
from neurosym_cli.policy import FullComm
from neurosym_cli.policy.gated import GatedComm, score_function_loss
from neurosym_cli.policy.transformer import CommTransformer
from neurosym_cli.rollout import rollout


def step(env, pol, comm, bucket, rng, horizon: int, detach: bool) -> float:
    """Seconds of one training step (rollout, loss, backward)."""
    discount = torch.ones(horizon)
    t0 = time.perf_counter()
    traj = rollout(env, pol, comm, bucket, rng, horizon, detach_state=detach, stats=False)
    loss = traj.cost.sum()
    if traj.logp is not None:
        loss = loss + score_function_loss(traj.cost, traj.comm_degree, traj.logp, discount, 0.1, True)
    loss.backward()
    return time.perf_counter() - t0


def read_curve(history: str) -> dict[str, list[float]]:
    """A training's history.csv -> cumulative wall seconds, rollouts, loss (and degree, for rl) per optimizer step."""
    import csv

    with open(history) as fh:
        rows = list(csv.DictReader(fh))
    t, out = 0.0, {"seconds": [], "rollouts": [], "loss": [], "degree": []}
    for r in rows:
        t += float(r["seconds"])
        out["seconds"].append(t)
        out["rollouts"].append(float(r["rollouts"]))
        out["loss"].append(float(r["loss"]))
        out["degree"].append(float(r["degree"]) if r.get("degree") else float("nan"))
    return out


def plot_curves(data: dict, path: str) -> None:
    """Training loss against wall time, and the rl gate's degree, from the curves of ``data``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4))
    for k, (name, c) in enumerate(data["curves"].items()):
        color = f"C{k}"  # one colour per training in both panels
        ax.plot([s / 60 for s in c["seconds"]], c["loss"], label=name, lw=1.2, color=color)
        if any(d == d for d in c["degree"]):  # rl only (NaN elsewhere)
            bx.plot(c["rollouts"], c["degree"], label=name, lw=1.2, color=color)
    ax.set_yscale("log")
    ax.set_xlabel("wall time (minutes, one thread each)")
    ax.set_ylabel("training loss (log scale)")
    ax.set_title("training loss against wall time")
    ax.legend(fontsize=8)
    bx.set_xlabel("training rollouts")
    bx.set_ylabel("max in+out of the gate's decisions")
    bx.set_title("rl: how much the agents talk while training")
    bx.legend(fontsize=8)
    fig.suptitle(f"{data['task']}, paper budget (train seed 0): the oracle's BPTT vs rl from scratch "
                 "(communication decisions as actions)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"drew {path}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--curves", default="", metavar="EXP", help="a run directory with train/oracle and an rl "
                    "model from scratch: plot their training curves instead of timing steps")
    ap.add_argument("--replot", default="", metavar="JSON", help="draw --plot from a saved --curves JSON")
    ap.add_argument("--plot", default="")
    ap.add_argument("--task", default="random-cross")
    ap.add_argument("--episodes", type=int, default=13, help="episodes per step (paper budget: 50 cut into ~4)")
    ap.add_argument("--horizon", type=int, default=0, help="0 = the task's")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--json", default="")
    a = ap.parse_args()
    if a.curves or a.replot:
        if a.replot:
            with open(a.replot) as fh:
                data = json.load(fh)
        else:
            from neurosym_cli.run.layout import ORACLE_DIR, RunFolder

            exp = RunFolder(a.curves)
            data = {"task": a.task, "curves": {"oracle (BPTT, full attention)":
                                               read_curve(str(exp.history_of(ORACLE_DIR)))}}
            for d in sorted(exp.trained_dir("").glob("rl-*-scratch")):
                data["curves"][f"{d.name} (rl from scratch)"] = read_curve(str(exp.history_of(d.name)))
            if a.json:
                with open(a.json, "w") as fh:
                    json.dump(data, fh)
        for name, c in data["curves"].items():
            tail = c["loss"][-5:]
            print(f"{name}: {c['rollouts'][-1]:.0f} rollouts in {c['seconds'][-1] / 60:.1f} min, final loss "
                  f"{sum(tail) / len(tail):.2f} (mean of the last {len(tail)} steps)")
        if a.plot:
            plot_curves(data, a.plot)
        return
    torch.set_num_threads(a.threads)
    task = compose_config("train", [f"task={a.task}"]).task
    env = make_task(task)
    horizon = a.horizon or task.horizon
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, task.rounds, ModelConfig())
    g = torch.Generator().manual_seed(0)
    rng = Rng(g, torch.device("cpu"))
    bucket = max(env.reset(a.episodes, g), key=lambda b: b.batch)
    comms = {"bptt (oracle, full attention)": FullComm(), "rl (gate + policy gradient)": GatedComm(task.rounds)}
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
