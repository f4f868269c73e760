"""The grids of `neurosym select` and `neurosym rl`: one job per config, ``jobs`` spawned processes at once
(stages/flow.py), each with one thread and plain log lines that name its config; a job's UserError comes back as a
value and stops the grid in one line, a dead worker says how to resume."""

from __future__ import annotations

import dataclasses
import time
from typing import Any, Callable

from ..config import RunConfig, UserError
from ..utils.console import clock, current_prefix, log, set_job_prefix
from . import RunInfo
from .flow import Job, Node, Worker, one, run_flow


def quiet_job(cfg: RunConfig, info: RunInfo) -> tuple[RunConfig, RunInfo]:
    """A grid job's config: plain progress lines, no program tables (many run at once)."""
    return dataclasses.replace(cfg, progress="plain"), RunInfo(True, info.log_dir)


def _job_entry(fn: Callable, cfg: RunConfig, info: RunInfo, name: Callable[[RunConfig], str]) -> dict[str, Any]:
    """A grid job: a UserError comes back as a value that names the grid point."""
    try:
        return fn(cfg, info)
    except UserError as e:
        return {"name": name(cfg), "error": str(e)}


def run_jobs(fn: Callable, cfgs: list[RunConfig], info: RunInfo, jobs: int, what: str, *,
             name: Callable[[RunConfig], str]) -> list[dict[str, Any]]:
    """``fn(cfg, info)`` (a module-level function: it is pickled for the workers) for every config, ``jobs``
    one-thread processes at once (1: in this process; stages/flow.py), results in the given order; ``what`` names a
    job and ``name`` a config in log lines and errors."""
    t0 = time.perf_counter()
    finished = []

    def done(r: dict[str, Any]) -> None:
        finished.append(r)
        if "error" in r:
            raise UserError(f"{what} {r['name']}: {r['error']}")
        log.info("%s %d/%d done: %s (%s elapsed)", what, len(finished), len(cfgs), r["name"],
                 clock(time.perf_counter() - t0))

    if jobs <= 1 or len(cfgs) == 1:
        out = []
        outer = current_prefix()  # a multirun's own prefix, kept before the grid point's and after the grid
        for c in cfgs:
            set_job_prefix(f"{outer} {name(c)}" if outer else name(c))  # the grid point's lines name it here too
            try:
                out.append(_job_entry(fn, c, info, name))
            finally:
                set_job_prefix(outer)
            done(out[-1])
        return out
    # one process per core: intra-op threads would only fight over the cores
    nodes = [Node(str(i), lambda c=c: one(Job(_job_entry, (fn, c, info, name), name(c)))) for i, c in enumerate(cfgs)]
    values = run_flow(nodes, min(jobs, len(cfgs)), worker=Worker.like_this_process(cfgs[0], threads=1),
                      on_result=done)
    return [values[str(i)] for i in range(len(cfgs))]
