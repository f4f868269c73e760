"""`neurosym synth`: synthesize a communication program from the trained oracle (paper sections 3.2, 3.4)."""

from __future__ import annotations

import hashlib
import time

import torch

from .. import __version__, artifacts, paths
from ..config import ConfigError, RunConfig
from ..dsl.printer import to_text
from ..envs import make_env
from ..synth.dataset import collect, from_payload, to_payload
from ..synth.objective import CachedScorer
from ..synth.search import RoundSpec, as_program, search_round
from ..utils.console import SearchDisplay, console, log, use_rich
from ..utils.device import resolve_device
from ..utils.io import save_program, write_csv, write_json
from ..utils.seeding import STREAM_SYNTH, STREAM_SYNTH_DATA, generator, seed_everything
from ._run import Context


def _fingerprint(policy) -> str:
    """Identifies the oracle's weights, so a dataset collected from other weights is never reused."""
    h = hashlib.sha1()
    for k, v in sorted(policy.state_dict().items()):
        h.update(k.encode())
        h.update(v.detach().cpu().contiguous().numpy().tobytes())
    return h.hexdigest()


def _dataset(cfg: RunConfig, env, policy, device):
    """The oracle dataset D, collected once per (oracle, rollouts, stride) and reused by every sweep job."""
    path = paths.dataset_file(cfg)
    oracle = _fingerprint(policy)
    if path.exists():
        try:
            payload = torch.load(path, map_location="cpu", weights_only=True)
            if payload.get("format") == "neurosym-dataset/1" and payload.get("oracle") == oracle:
                log.info("reusing the dataset %s", path)
                return from_payload(payload)
            log.info("the dataset %s came from other oracle weights; collecting it again", path)
        except Exception:
            log.warning("unreadable dataset %s; collecting it again", path)
    t0 = time.perf_counter()
    data = collect(env, policy, cfg.budget.synth_rollouts, cfg.synth.stride, generator(cfg.seed, STREAM_SYNTH_DATA),
                   device)
    artifacts.save_checkpoint(path, {**to_payload(data), "oracle": oracle})
    pairs = sum(b.states * b.n_agents ** 2 for b in data)
    log.info("collected D: %d rollouts, %d states, %.1fM agent pairs in %.0f s -> %s", cfg.budget.synth_rollouts,
             sum(b.states for b in data), pairs / 1e6, time.perf_counter() - t0, path)
    return data


def _backend(name: str, device: torch.device) -> str:
    """synth.backend, checked against this machine: numba needs the package and a CPU device."""
    from ..synth import kernels

    if name == "numba" and not kernels.AVAILABLE:
        raise ConfigError("synth.backend=numba needs numba (pip install numba), or use synth.backend=auto")
    if name == "numba" and device.type != "cpu":
        raise ConfigError(f"synth.backend=numba runs on the CPU only; this run uses device {device} "
                          "(use synth.backend=auto or device=cpu)")
    return name


def run(cfg: RunConfig, ctx: Context) -> dict:
    if cfg.baseline.comm not in ("program", "tree"):
        raise ConfigError(f"synth makes programs (baseline=prog, det-prog) or trees (baseline=dt), "
                          f"not {cfg.baseline.name}")
    out = paths.synth_dir(cfg)
    result = out / ("tree.json" if cfg.baseline.comm == "tree" else "program.txt")
    if result.exists() and (out / "summary.json").exists() and not cfg.overwrite:
        log.info("already synthesized: %s (overwrite=true searches again)", result)
        return {"program": str(result)}
    device = resolve_device(cfg.device)
    seed_everything(cfg.seed)
    payload = artifacts.load_checkpoint(paths.oracle_checkpoint(cfg), paths.train_command(cfg, oracle=True))
    policy = artifacts.policy_from_payload(payload).to(device).eval()
    env = make_env(cfg.task, cfg.horizon)
    data = _dataset(cfg, env, policy, device)
    if cfg.baseline.comm == "tree":
        return _synth_trees(cfg, ctx, policy, data, out)
    spec = RoundSpec(cfg.budget.mcmc_steps, cfg.synth.restarts, cfg.synth.final_fraction, cfg.synth.temperature,
                     cfg.rules, cfg.synth.max_depth, cfg.baseline.det)
    results, trace, rounds = [], [], []
    rich = use_rich(cfg.progress, ctx.multirun)
    for r in range(cfg.task.rounds):
        # appendix A: each round's program is searched alone, the other rounds keep soft attention
        scorer = CachedScorer(policy, env, cfg.task.kind, data, r, cfg.features, cfg.lam, cfg.synth.objective,
                              cfg.rules, cfg.synth.random_samples, generator(cfg.seed, STREAM_SYNTH, r), device,
                              backend=_backend(cfg.synth.backend, device))
        label = f"synth {cfg.task.name} {paths.program_tag(cfg)}" + (f" round {r + 1}" if cfg.task.rounds > 1 else "")
        with SearchDisplay(label, spec.steps, cfg.lam, rich) as disp:
            res = search_round(scorer, spec, f"{cfg.seed}/{r}/{paths.program_tag(cfg)}",
                               generator(cfg.seed, STREAM_SYNTH, 100 + r), disp.update)
        full = scorer.full_score(as_program([res])) if cfg.task.rounds == 1 else None
        results.append(res)
        trace += [{"round": r + 1, **row} for row in res.trace]
        rounds.append({"round": r + 1, "objective": res.best_score.total, "l1": res.best_score.l1,
                       "degree": res.best_score.degree, "seconds": res.seconds,
                       "proposals_per_second": res.proposals_per_second, "acceptance": res.acceptance(),
                       "proposed": dict(res.proposed), "rows_recomputed": scorer.rows_recomputed,
                       "backend": "numba" if scorer.compiled else "torch",
                       "full_forward_check": None if full is None else full.total})
    program = as_program(results)
    header = [f"neurosym program for {cfg.task.name}: rules={cfg.rules} lam={cfg.lam:g} features={cfg.features}"
              f" det={str(cfg.baseline.det).lower()} seed={cfg.seed} budget={cfg.budget.name}"]
    header += [f"round {x['round']}: objective {x['objective']:.4f} = L1 {x['l1']:.4f} + {cfg.lam:g} x degree "
               f"{x['degree']:.4f}" for x in rounds]
    save_program(out / "program.txt", to_text(program), header)
    write_csv(out / "trace.csv", trace)
    write_json(out / "summary.json", {
        "command": "synth", "version": __version__, "task": cfg.task.name, "tag": paths.program_tag(cfg),
        "rules": cfg.rules, "lam": cfg.lam, "features": cfg.features, "det": cfg.baseline.det,
        "objective": cfg.synth.objective, "steps": spec.steps, "dataset": str(paths.dataset_file(cfg)),
        "dataset_states": sum(b.states for b in data), "rounds": rounds, "program": to_text(program),
        "config": ctx.config_dict(),
    })
    console.print(f"[green]synthesized[/] {out / 'program.txt'}")
    if not ctx.multirun:
        from .show_program import render

        render(program, rounds, cfg.lam)
    return {"program": str(out / "program.txt"), "objective": sum(x["objective"] for x in rounds)}


def _synth_trees(cfg: RunConfig, ctx: Context, policy, data, out) -> dict:
    """dt (appendix B): per round, label every pair of D by the greedy global hard attention with in- and
    out-degree <= K from the oracle's soft attention, then fit a tree on the pair features."""
    from ..envs.features import PairFeatures
    from ..synth.tree import fit_tree, greedy_hard_attention, soft_attention

    policy = policy.cpu()
    trees, rounds = [], []
    for r in range(cfg.task.rounds):
        xs, ys = [], []
        for b in data:
            labels = greedy_hard_attention(soft_attention(policy, b, r), cfg.rules)  # (S, N, N)
            feats = PairFeatures(cfg.task.kind, b.agent, b.rel, cfg.features)
            off = ~torch.eye(b.n_agents, dtype=torch.bool).expand(b.states, -1, -1)
            xs.append(torch.stack([feats[f].expand(b.states, b.n_agents, b.n_agents)[off] for f in feats.names], -1))
            ys.append(labels[off])
            names = feats.names
        x, y = torch.cat(xs), torch.cat(ys)
        g = generator(cfg.seed, STREAM_SYNTH, 200 + r)
        keep = torch.randperm(len(y), generator=g)[:300_000]  # bound the fitting time
        tree, info = fit_tree(x[keep], y[keep], names, (3, 5, 10, 20), cfg.seed)
        trees.append(tree)
        rounds.append({"round": r + 1, "pairs": int(len(keep)), "positive_fraction": float(y[keep].float().mean()),
                       **info, "nodes": len(tree.left)})
        log.info("dt round %d: depth %d, validation accuracy %.3f, %d nodes", r + 1, info["depth"],
                 info["validation_accuracy"][info["depth"]], len(tree.left))
    write_json(out / "tree.json", {"rounds": [t.to_dict() for t in trees]})
    write_json(out / "summary.json", {"command": "synth", "version": __version__, "task": cfg.task.name,
                                      "tag": paths.program_tag(cfg), "rules": cfg.rules, "rounds": rounds,
                                      "config": ctx.config_dict()})
    console.print(f"[green]fitted[/] {out / 'tree.json'}")
    return {"tree": str(out / "tree.json")}
