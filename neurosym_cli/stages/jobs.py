"""The process pool of the grid verbs (`neurosym select`, `neurosym rl`): one job per config, ``jobs`` spawned
processes at once, each with one thread and plain log lines that name its config; a job's UserError comes back
as a value and stops the grid in one line, a dead worker says how to resume."""

from __future__ import annotations

import dataclasses
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from multiprocessing import get_context
from typing import Any, Callable

from ..config import RunConfig, UserError
from ..utils.console import clock, log
from . import RunInfo


def quiet_job(cfg: RunConfig, info: RunInfo) -> tuple[RunConfig, RunInfo]:
    """A grid job's config: plain progress lines, no program tables (many run at once)."""
    return dataclasses.replace(cfg, progress="plain"), RunInfo(True, info.log_dir)


def _worker_init() -> None:
    """A pool worker: one thread, and plain log lines on stdout (a spawned process has no logging set up, so its
    progress lines would be lost)."""
    import logging
    import sys

    import torch

    torch.set_num_threads(1)  # one process per core: intra-op threads would only fight over the cores
    handler = logging.StreamHandler(sys.stdout)
    handler.setFormatter(logging.Formatter("[%(asctime)s] %(levelname)s %(message)s", "%H:%M:%S"))
    root = logging.getLogger()
    root.handlers[:] = [handler]
    root.setLevel(logging.INFO)


def _job_entry(fn: Callable, cfg: RunConfig, info: RunInfo, name: Callable[[RunConfig], str]) -> dict[str, Any]:
    """A pool worker's job: its log lines name the grid point; a UserError comes back as a value."""
    from ..utils.console import set_job_prefix

    set_job_prefix(name(cfg))
    try:
        return fn(cfg, info)
    except UserError as e:
        return {"name": name(cfg), "error": str(e)}
    finally:
        set_job_prefix("")


def run_jobs(fn: Callable, cfgs: list[RunConfig], info: RunInfo, jobs: int, what: str, *,
             name: Callable[[RunConfig], str]) -> list[dict[str, Any]]:
    """``fn(cfg, info)`` (a module-level function: it is pickled for the workers) for every config, ``jobs``
    processes at once (1: in this process), results in the given order; ``what`` names a job and ``name`` a config
    in log lines and errors."""
    t0 = time.perf_counter()
    results: dict[int, dict[str, Any]] = {}

    def done(i: int, r: dict[str, Any]) -> None:
        results[i] = r
        if "error" in r:
            raise UserError(f"{what} {r['name']}: {r['error']}")
        log.info("%s %d/%d done: %s (%s elapsed)", what, len(results), len(cfgs), r["name"],
                 clock(time.perf_counter() - t0))

    if jobs <= 1 or len(cfgs) == 1:
        for i, c in enumerate(cfgs):
            done(i, _job_entry(fn, c, info, name))
    else:
        with ProcessPoolExecutor(min(jobs, len(cfgs)), mp_context=get_context("spawn"),
                                 initializer=_worker_init) as pool:
            futures = {pool.submit(_job_entry, fn, c, info, name): i for i, c in enumerate(cfgs)}
            try:
                for f in as_completed(futures):
                    done(futures[f], f.result())
            except BrokenProcessPool as e:  # a worker was killed (out of memory, a signal): finished jobs are kept
                raise UserError(f"a {what} process died ({e}); what finished is on disk, rerun the same command "
                                "to resume") from None
            except BaseException:
                for f in futures:
                    f.cancel()
                raise
    return [results[i] for i in range(len(cfgs))]
