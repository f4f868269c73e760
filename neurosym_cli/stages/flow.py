"""Stages of one run at once: a small scheduler over a dependency graph, each job in its own single-thread process.

A node of the graph is a generator that yields batches of ``Job``s and is sent back their results (a plain stage
is one batch of one job; the pipeline's front selection is three batches: validations, retrainings, validations),
between batches it runs in this process (reading a front, writing candidate files, the pick: cheap). A node starts
when every node it ``needs`` is done and no running node ``holds`` the same resource (two searches of one oracle
share its dataset D: the second waits and reuses it). Jobs run ``jobs`` at a time in spawned processes with one
thread each (stages/jobs.py's workers), or one after the other in this process when ``jobs`` is 1. Every stage
seeds itself (utils/seeding.py), so the numbers do not depend on the order nor on the process a stage ran in.
"""

from __future__ import annotations

import dataclasses
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from multiprocessing import get_context
from typing import Any, Callable, Generator, Sequence

from ..config import UserError

Batch = list["Job"]
Flow = Generator[Batch, list, Any]
"""a node's work: yields batches of jobs, is sent each batch's results (in order), returns the node's value"""


@dataclasses.dataclass(frozen=True)
class Job:
    """One call ``fn(*args)``, run in a worker (``fn`` is a module-level function, pickled) or in this process;
    ``name`` prefixes its log lines in a worker."""

    fn: Callable[..., Any]
    args: tuple
    name: str


@dataclasses.dataclass
class Node:
    """A node of the graph: ``start()`` makes its flow when its ``needs`` (keys) are done; ``holds``: a resource no
    two running nodes share (None: none); ``on_start``: called in this process as it starts."""

    key: str
    start: Callable[[], Flow]
    needs: tuple[str, ...] = ()
    holds: str | None = None
    on_start: Callable[[], None] | None = None


def one(job: Job) -> Flow:
    """The flow of a node that is one job: its result is the node's value."""
    (result,) = yield [job]
    return result


def _call(fn: Callable[..., Any], args: tuple, name: str) -> Any:
    """A job inside a worker: its log lines name it."""
    from ..utils.console import set_job_prefix

    set_job_prefix(name)
    try:
        return fn(*args)
    finally:
        set_job_prefix("")


class _Running:
    """A started node: its flow, the batch it waits for, the results of that batch so far."""

    def __init__(self, node: Node, flow: Flow) -> None:
        self.node, self.flow, self.results, self.waiting = node, flow, [], 0


def run_flow(nodes: Sequence[Node], jobs: int, *, on_result: Callable[[Any], None] | None = None) -> dict[str, Any]:
    """Run every node's flow in dependency order, ``jobs`` jobs at a time (1: in this process, in the nodes' order
    as far as the graph allows); returns each node's value by key. ``on_result``: called in this process with every
    job's result as it comes. An error in any job stops the flow: jobs still running are stopped (what each
    stage finished is on disk, and a rerun resumes it) and the error is raised here."""
    keys = {n.key for n in nodes}
    missing = sorted({k for n in nodes for k in n.needs} - keys)
    if missing:
        raise ValueError(f"flow: nodes need unknown keys {missing}")
    todo, done, running = list(nodes), {}, {}
    queue: list[tuple[_Running, int, Job]] = []  # jobs ready to start, in order
    futures: dict[Future, tuple[_Running, int]] = {}
    pool = None
    if jobs > 1:
        from .jobs import _worker_init

        pool = ProcessPoolExecutor(jobs, mp_context=get_context("spawn"), initializer=_worker_init)

    def advance(r: _Running, sent: list | None) -> None:
        """Send a batch's results to a flow (None: start it); queue its next batch or finish the node."""
        try:
            batch = next(r.flow) if sent is None else r.flow.send(sent)
        except StopIteration as stop:
            done[r.node.key] = stop.value
            del running[r.node.key]
            return
        r.results, r.waiting = [None] * len(batch), len(batch)
        if not batch:  # an empty batch: sent back at once
            advance(r, [])
            return
        queue.extend((r, i, job) for i, job in enumerate(batch))

    def start_ready() -> None:
        """Start ready nodes, in their order, while a job slot is free (in this process: when nothing runs)."""
        held = {r.node.holds for r in running.values() if r.node.holds}
        while (len(futures) + len(queue) < jobs) if pool is not None else not running:
            node = next((n for n in todo if all(k in done for k in n.needs)
                         and (n.holds is None or n.holds not in held)), None)
            if node is None:
                return
            todo.remove(node)
            if node.holds:
                held.add(node.holds)
            if node.on_start:
                node.on_start()
            r = running[node.key] = _Running(node, node.start())
            advance(r, None)

    def submit() -> None:
        while queue and (pool is None or len(futures) < jobs):
            r, i, job = queue.pop(0)
            f: Future = Future()
            if pool is None:
                try:
                    f.set_result(job.fn(*job.args))
                except BaseException as e:  # noqa: BLE001 - raised where the result is read, as a worker's would be
                    f.set_exception(e)
            else:
                f = pool.submit(_call, job.fn, job.args, job.name)
            futures[f] = (r, i)
            if pool is None:
                return

    try:
        while todo or running:
            start_ready()
            submit()
            if not futures:
                if not todo and not running:  # the last nodes ended without a job
                    break
                raise ValueError(f"flow: nothing can start ({', '.join(n.key for n in todo)}): a cycle")
            finished, _ = wait(list(futures), return_when=FIRST_COMPLETED)
            for f in finished:
                r, i = futures.pop(f)
                try:
                    result = f.result()
                except BrokenProcessPool as e:  # a worker was killed (out of memory, a signal)
                    raise UserError(f"a pipeline process died ({e}); what finished is on disk, rerun the same "
                                    "command to resume") from None
                if on_result is not None:
                    on_result(result)
                r.results[i] = result
                r.waiting -= 1
                if r.waiting == 0:
                    advance(r, r.results)
    except BaseException:
        if pool is not None:  # stop the stages still running: each resumes from its checkpoint on a rerun
            for p in list(getattr(pool, "_processes", {}).values()):
                p.terminate()
            pool.shutdown(wait=False, cancel_futures=True)
            pool = None
        raise
    finally:
        if pool is not None:
            pool.shutdown()
    return done
