"""Training rollouts/s with the step eager (compile=off) against compiled (compile=on) and against the fused pair
kernels (compile=fused), ratios measured in one process, and the losses of each over the same optimizer steps
(issue 39; docs/performance.md, 'The compiled step').

    python benchmarks/bench_compile.py                          # random-cross, B = 50, T = 200, threads 1 and 2
    python benchmarks/bench_compile.py --modes eager,fused      # without torch.compile's minutes of compiling
    python benchmarks/bench_compile.py --batch 10 --horizon 20 --steps 5      # a quick look
    python benchmarks/bench_compile.py --round                  # one dense round, eager against fused, N = 10-200
    python benchmarks/bench_compile.py --swarm 100 --batch 4 --horizon 50 --modes eager,fused   # swarm, N = 200
    python benchmarks/bench_compile.py --device cuda            # B = 50 ... 4096: eager, compiled, captured
    python benchmarks/bench_compile.py --profile --modes eager,fused --steps 4   # where a training step's time goes

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


MODES = {"eager": "off", "compiled": "on", "captured": "on", "fused": "fused"}
"""benchmark mode -> compile= value (captured: compiled with CUDA graphs, the options say so)"""


def _steps(env, mode: str, *, batch: int, horizon: int, device: torch.device, options: dict | None = None):
    """Optimizer steps under compile=mode, one per ``next``: yields (loss, wall seconds, CPU seconds of this
    process: what the step cost where other jobs share the cores). The mode is put in effect
    again before each step, and so is torch's global random state (dropout's), so that steps of several modes can
    alternate in one process and each still draws what it would alone."""
    compiling.configure(MODES[mode], device.type)
    stepmod.reset_compiled()
    torch.manual_seed(0)
    policy = CommTransformer.for_task(env, ModelConfig()).to(device)
    opt = torch.optim.Adam(policy.parameters(), 1e-3)
    gen = torch.Generator().manual_seed(1)
    rng = Rng(gen, device)
    mine = torch.random.get_rng_state(), (torch.cuda.get_rng_state() if device.type == "cuda" else None)
    while True:
        torch.random.set_rng_state(mine[0])
        if mine[1] is not None:
            torch.cuda.set_rng_state(mine[1])
        compiling.configure(MODES[mode], device.type)
        stepmod.OPTIONS.clear()
        stepmod.OPTIONS.update(options or {"dynamic": False})
        t0, c0 = time.perf_counter(), time.process_time()
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
        mine = torch.random.get_rng_state(), (torch.cuda.get_rng_state() if device.type == "cuda" else None)
        yield total, time.perf_counter() - t0, time.process_time() - c0


def _summary(mode: str, batch: int, done: list[tuple[float, float, float]], record: dict) -> dict:
    """A mode's (loss, wall s, CPU s) per step -> losses, the first step's wall seconds (compilation included),
    rollouts per wall second and per CPU second over the others (their median step: a busy machine slows some
    steps, not the typical one)."""
    rest = done[1:] or done
    wall, cpu = (sorted(r[k] for r in rest)[len(rest) // 2] for k in (1, 2))
    return {"mode": mode, "losses": [r[0] for r in done], "first_s": done[0][1], "rollouts_per_s": batch / wall,
            "rollouts_per_cpu_s": batch / cpu, "compile": record}


def train(env, mode: str, *, batch: int, horizon: int, steps: int, device: torch.device, options: dict | None = None
          ) -> dict:
    """``steps`` optimizer steps under compile=mode -> losses per step, seconds of the first step (compilation
    included) and rollouts/s over the others."""
    it = _steps(env, mode, batch=batch, horizon=horizon, device=device, options=options)
    done = [next(it) for _ in range(steps)]
    return _summary(mode, batch, done, compiling.record())


def alternated(env, modes: list[str], *, batch: int, horizon: int, steps: int, device: torch.device) -> list[dict]:
    """``train`` for each mode, their steps taken in turn (eager, fused, eager, fused, ...): on a machine shared
    with other jobs both see the same load, so their ratio holds where back-to-back runs drift apart."""
    its = {m: _steps(env, m, batch=batch, horizon=horizon, device=device) for m in modes}
    done: dict[str, list] = {m: [] for m in modes}
    records = {}
    for _ in range(steps):
        for m in modes:
            done[m].append(next(its[m]))
            records[m] = compiling.record()
    return [_summary(m, batch, done[m], records[m]) for m in modes]


def round_rows(serves_from: int, shapes=((12, 10), (12, 20), (12, 40), (4, 100), (2, 200)), reps: int = 5
               ) -> list[dict]:
    """One dense round's forward and backward (logits, aggregate, post block) at (B, N), eager against the fused
    pair kernels, taken in turn, median CPU ms of this process over ``reps`` tries; and the MiB the round keeps
    for backward (autograd's saved tensors). ``serves_from``: the N from which compile=fused uses the kernels."""
    from statistics import median

    from neurosym_cli.policy.transformer import CommRound

    torch.manual_seed(0)
    layer = CommRound(16, 32, 0.0)

    def once(b: int, n: int, mode: str) -> tuple[float, float]:
        compiling.configure(MODES[mode])
        h, rel = torch.randn(b, n, 16, requires_grad=True), torch.randn(b, n, n, 2, requires_grad=True)
        mask, kept = torch.rand(b, n, n) > 0.2, []
        c0 = time.process_time()
        with torch.autograd.graph.saved_tensors_hooks(lambda t: kept.append(t.numel() * t.element_size()) or t,
                                                      lambda t: t):
            y, _ = layer.aggregate(h, layer.logits(h, rel), mask, rel)
        y.sum().backward()
        return (time.process_time() - c0) * 1e3, sum(kept) / 2**20

    rows = []
    for b, n in shapes:
        runs: dict[str, list] = {"eager": [], "fused": []}
        for _ in range(reps):
            for m in runs:
                runs[m].append(once(b, n, m))
        e, f = (median(x for x, _ in runs[m]) for m in runs)
        rows.append({"batch": b, "agents": n, "eager_ms": round(e, 3), "fused_ms": round(f, 3),
                     "ratio": round(e / f, 2), "eager_saved_mib": round(runs["eager"][0][1], 2),
                     "fused_saved_mib": round(runs["fused"][0][1], 2),
                     "fused_serves": n >= serves_from})
        print(json.dumps(rows[-1]), flush=True)
    return rows


PARTS = {
    "observe (the task's observation and noise)": [("formation.py", "observe"), ("tasks/base.py", "observe")],
    "transformer forward (rounds, read-out)": [("policy/transformer.py", "forward")],
    "task dynamics and cost": [("formation.py", "step"), ("formation.py", "cost")],
    "backward: autograd's own ops": [("~", "<method 'run_backward' of 'torch._C._EngineBase' objects>")],
    "optimizer (Adam)": [("optim/adam.py", "step")],
}
"""part of a training step -> the (file suffix, function) whose cumulative cProfile time it is; the fused
kernels' backward, called from autograd's engine, is counted apart ("backward: fused pair kernels")"""


def profile_rows(env, mode: str, *, batch: int, horizon: int, steps: int) -> dict:
    """Where a training step's CPU time goes under compile=mode: cProfile over ``steps`` optimizer steps (after one
    not counted), as seconds per step for each of ``PARTS``, the fused kernels' backward apart, and the rest (the
    rollout loop, the loss, Python). cProfile's own overhead inflates the Python-heavy parts a little."""
    import cProfile
    import pstats

    it = _steps(env, mode, batch=batch, horizon=horizon, device=torch.device("cpu"))
    next(it)
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(steps):
        next(it)
    prof.disable()
    st = pstats.Stats(prof).stats  # (file, line, name) -> (calls, primitive calls, tottime, cumtime, callers)
    total = sum(v[2] for v in st.values())

    def cum(file: str, name: str, own: bool = False) -> float:
        return sum(v[2] if own else v[3] for (f, _, n), v in st.items() if f.endswith(file) and n == name)

    rows = {part: sum(cum(f, n) for f, n in keys) for part, keys in PARTS.items()}
    back = sum(v[3] for (f, _, n), v in st.items() if f.endswith("edge_kernels.py") and n.endswith("_bwd"))
    rows["backward: autograd's own ops"] -= back
    rows["backward: fused pair kernels"] = back
    rows["the rest (rollout loop, loss, Python)"] = total - sum(rows.values())
    out = {"mode": mode, "batch": batch, "horizon": horizon, "steps": steps, "total_s_per_step": total / steps,
           "parts_s_per_step": {k: round(v / steps, 3) for k, v in rows.items()}}
    print(json.dumps(out), flush=True)
    return out


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
    ap.add_argument("--modes", help="the modes, eager first (default: eager,compiled,fused on a CPU, "
                    "eager,compiled,captured on a GPU)")
    ap.add_argument("--json", default="", help="also write the rows here")
    ap.add_argument("--swarm", type=int, default=0, help="the swarm with this many agents per group (two groups; "
                    "dense below task.sparse_from = 256 agents) instead of random-cross")
    ap.add_argument("--round", action="store_true", help="one dense round at N = 10 to 200, eager against fused "
                    "(the fused kernels serving at every N), and stop")
    ap.add_argument("--profile", action="store_true", help="where a training step's CPU time goes, per mode "
                    "(cProfile over --steps steps at the first of --threads), and stop")
    ap.add_argument("--fused-from", type=int, default=None, help="the team size from which compile=fused's kernels "
                    "serve a round (default: edge_kernels.FUSED_FROM)")
    args = ap.parse_args()
    if args.fused_from is not None:
        from neurosym_cli.policy import edge_kernels

        edge_kernels.FUSED_FROM = args.fused_from
    modes = (args.modes or ("eager,compiled,captured" if args.device == "cuda" else "eager,compiled,fused")).split(",")
    if modes[0] != "eager" or any(m not in MODES for m in modes):
        sys.exit(f"bench_compile: --modes is eager first, then any of {', '.join(MODES)}")
    if args.swarm:
        from neurosym_cli.tasks.swarm import SwarmConfig

        env = make_task(SwarmConfig(name="swarm", agents_per_group=args.swarm), horizon=args.horizon)
    else:
        env = make_task(CrossConfig(name="random-cross"), horizon=args.horizon)
    rows = []
    if args.profile:
        torch.set_num_threads(int(args.threads.split(",")[0]))
        rows = [profile_rows(env, m, batch=args.batch, horizon=args.horizon, steps=args.steps) for m in modes]
        args.device = "none"
    if args.round:
        from neurosym_cli.policy import edge_kernels

        torch.set_num_threads(1)
        serves_from, edge_kernels.FUSED_FROM = edge_kernels.FUSED_FROM, 0  # measured where they do not serve too
        rows = round_rows(serves_from)
        args.device = "none"
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
                    for m in modes]
            for r in runs:
                rows.append({"device": "cuda", "batch": b, **{k: r[k] for k in ("mode", "rollouts_per_s", "first_s")},
                             "vs_eager": r["rollouts_per_s"] / runs[0]["rollouts_per_s"],
                             "loss_rel_diff": agreement(runs[0]["losses"], r["losses"]),
                             "in_effect": r["compile"]["in_effect"], "why_off": r["compile"]["why_off"]})
                print(json.dumps(rows[-1]), flush=True)
    elif args.device == "cpu":
        dev = torch.device("cpu")
        for th in (int(x) for x in args.threads.split(",")):
            torch.set_num_threads(th)
            runs = alternated(env, modes, batch=args.batch, horizon=args.horizon, steps=args.steps, device=dev)
            for r in runs[1:]:
                rows.append({"device": "cpu", "task": env.cfg.name, "agents": 2 * args.swarm or "10-40",
                             "threads": th, "batch": args.batch, "horizon": args.horizon,
                             "mode": r["mode"], "eager_rollouts_per_s": runs[0]["rollouts_per_s"],
                             "rollouts_per_s": r["rollouts_per_s"],
                             "ratio": r["rollouts_per_s"] / runs[0]["rollouts_per_s"],
                             "cpu_ratio": r["rollouts_per_cpu_s"] / runs[0]["rollouts_per_cpu_s"],
                             "compile_s": r["compile"]["compile_seconds"], "first_step_s": r["first_s"],
                             "in_effect": r["compile"]["in_effect"],
                             "loss_rel_diff": agreement(runs[0]["losses"], r["losses"])})
                print(json.dumps(rows[-1]), flush=True)
    if args.json:
        from pathlib import Path

        from neurosym_cli.utils.io import write_json

        write_json(Path(args.json), rows)


if __name__ == "__main__":
    main()
