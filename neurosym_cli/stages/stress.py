"""`neurosym stress`: trained baselines evaluated zero-shot, without retraining, at other team sizes and under link
failure (the questions users ask beyond the paper: does a policy trained at one N hold at another, and what
happens when links fail?). Writes <exp_dir>/stress/stress.json, stress.csv and stress.png."""

from __future__ import annotations

import dataclasses
import time
from typing import Any

from ..baselines import run_args
from ..schemes import with_run
from ..config import ConfigError, RunConfig, UserError
from ..run import RunDir
from ..policy.footprint import DoesNotFit
from ..degrees import LEGEND, METRICS
from .front_select import program_for
from ..utils.console import clock, log, say
from ..utils.cpu import runtime
from ..utils.io import write_csv, write_json
from . import RunInfo



def conditions(cfg: RunConfig) -> list[tuple[str, int, float]]:
    """(axis, agents per group, link failure): every team size at no failure, then every failure rate at the
    task's own team size."""
    n0 = cfg.task.agents_per_group
    out = [("agents", n, 0.0) for n in cfg.stress.agents]
    out += [("failure", n0, f) for f in cfg.stress.failure]
    return out


def stress_point(cfg: RunConfig, agents: int, failure: float) -> dict[str, Any]:
    """The baseline of ``cfg`` (its trained weights, its program) on the test seeds with ``agents`` per group and
    link failure ``failure``: mean, std and 95 % half-width of each metric."""
    from ..evaluation import evaluate, summarize
    from ..utils.device import resolve_device
    from ..utils.seeding import seed_everything
    from ..run.models import load_baseline

    from ..tasks import make_task, require

    task = dataclasses.replace(cfg.task, agents_per_group=agents, link_failure=failure)
    # the memory check counts the episodes evaluated at once: stress.seeds seeds' worth, not the budget's
    c = dataclasses.replace(cfg, task=task, budget=dataclasses.replace(cfg.budget, eval_seeds=cfg.stress.seeds))
    # exp_dir is unchanged: the weights and programs trained at the task's N
    env = require(make_task(cfg.task, cfg.horizon), "with_team_size", "stress (other team sizes)")(agents)
    device = resolve_device(c.device)
    seed_everything(c.seed)
    policy, env, comm = load_baseline(c, device, env)
    rows = evaluate(env, policy, comm, list(range(cfg.stress.seeds)), device, c.task.detach_state)
    s = summarize(rows)
    return {m: {k: s[m][k] for k in ("mean", "std", "ci95")} for m in METRICS}


def run_stress(cfg: RunConfig, info: RunInfo) -> dict[str, Any]:
    """Every (baseline, condition) of ``conditions``; baselines without trained weights are skipped by name."""
    from ..tasks import make_task, require

    # a task whose programs read features fixed by its N (unlabeled-goals: one per goal) cannot change its team
    require(make_task(cfg.task, cfg.horizon), "with_team_size", "stress (other team sizes)")
    if cfg.task.link_failure > 0:
        raise ConfigError("stress sets the link failure itself (stress.failure); run it on the failure-free task")
    conds = conditions(cfg)
    t0 = time.perf_counter()
    results: list[dict[str, Any]] = []
    skipped: dict[str, str] = {}
    stops: dict[str, dict[str, Any]] = {}  # label -> the smallest team that does not fit, and why
    for name in cfg.stress.baselines:
        b = dataclasses.replace(cfg, baseline=with_run(cfg, name), cmd="eval", program=program_for(cfg, name))
        label = RunDir(b).label
        done: dict[tuple[int, float], dict] = {}  # the task's own size at no failure is on both axes: run it once
        for axis, n, f in conds:
            n_total = dataclasses.replace(cfg.task, agents_per_group=n).max_agents
            try:
                r = done[(n, f)] if (n, f) in done else stress_point(b, n, f)
                done[(n, f)] = r
            except DoesNotFit as e:  # estimated before allocating: the baseline stops here, the others go on
                if label not in stops or n_total < stops[label]["max_agents"]:
                    stops[label] = {"agents_per_group": n, "max_agents": n_total, "why": str(e)}
                log.warning("stress: %s stops at %d per group: %s", label, n, e)
                continue
            except UserError as e:  # not trained here (or no program): say so and go on with the others
                skipped[label] = str(e)
                log.warning("stress: skipped %s: %s", label, e)
                break
            results.append({"baseline": name, "label": label, "axis": axis, "agents_per_group": n,
                            "max_agents": n_total, "link_failure": f, **r})
            log.info("stress %s: %d per group, link failure %g: loss %.3f, max in-degree %.2f (%s elapsed)", label,
                     n, f, r["cost"]["mean"], r["max_in"]["mean"], clock(time.perf_counter() - t0))
    if not results and not stops:
        raise UserError("stress: no baseline of stress.baselines is trained here; "
                        f"`neurosym pipeline {run_args(cfg)}` makes them")
    out = RunDir(cfg)
    write_json(out.stress_file(), {"task": cfg.task.name, "trained_agents_per_group": cfg.task.agents_per_group,
                                   "seeds": cfg.stress.seeds, "results": results, "skipped": skipped, "stops": stops,
                                   "seconds": time.perf_counter() - t0, "runtime": runtime(),
                                   "config": cfg.record()})
    write_csv(out.stress_file(".csv"), [{k: (v["mean"] if isinstance(v, dict) else v) for k, v in r.items()}
                                        for r in results])
    from ..plotting import stress_plot
    from ..tasks.base import cost_words

    png = stress_plot(results, cfg, out.stress_file(".png"), cost_words(cfg.task)) if cfg.plots else None
    print_stress(results, cfg, stops)
    say(f"[green]stress done[/] in {clock(time.perf_counter() - t0)}: {out.stress_file('.csv')}"
        + (f", {png}" if png else ""))
    return {"points": len(results)}


def print_stress(results: list[dict], cfg: RunConfig, stops: dict[str, dict] | None = None) -> None:
    from rich.table import Table

    from ..utils.console import console

    for axis, head in (("agents", "agents per group"), ("failure", "link failure")):
        rows = [r for r in results if r["axis"] == axis]
        if not rows:
            continue
        keys = sorted({r["agents_per_group"] if axis == "agents" else r["link_failure"] for r in rows})
        t = Table(title=f"zero-shot {head} ({cfg.task.name}, trained at {cfg.task.agents_per_group} per group, "
                        f"{cfg.stress.seeds} test seeds): loss / max in / max out",
                  caption=LEGEND, caption_justify="left",
                  header_style="bold")
        t.add_column("baseline")
        for k in keys:
            if axis == "failure":
                t.add_column(f"{k:g}", justify="right")
                continue
            n_max = dataclasses.replace(cfg.task, agents_per_group=k).max_agents
            t.add_column(f"{k} (N ≤ {n_max})", justify="right")
        for label in dict.fromkeys(r["label"] for r in rows):
            cells = []
            for k in keys:
                r = next((r for r in rows if r["label"] == label and
                          (r["agents_per_group"] if axis == "agents" else r["link_failure"]) == k), None)
                cells.append("-" if r is None else f"{r['cost']['mean']:.2f} / {r['max_in']['mean']:.2f} / "
                                                   f"{r['max_out']['mean']:.2f}")
            t.add_row(label, *cells)
        console.print(t)
    for label in dict.fromkeys(r["label"] for r in results if r["axis"] == "agents"):
        ran = max(r["max_agents"] for r in results if r["label"] == label and r["axis"] == "agents")
        stop = (stops or {}).get(label)
        say(f"{label}: ran up to N = {ran:,}" + (f"; stops at N = {stop['max_agents']:,}: {stop['why']}" if stop
                                                 else "; every size of stress.agents fits"))
    for label, stop in (stops or {}).items():
        if not any(r["label"] == label for r in results):
            say(f"{label}: stops at N = {stop['max_agents']:,}: {stop['why']}")
