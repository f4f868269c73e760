"""Work of one command at once: a small scheduler over a dependency graph, each job in its own worker process.

A node of the graph is a generator that yields batches of ``Job``s and is sent back their results (a plain stage
is one batch of one job; the pipeline's front selection is three batches: validations, retrainings, validations);
between batches it runs in this process (reading a front, writing candidate files, the pick: cheap). A node starts
when every node it ``needs`` is done. Jobs run ``jobs`` at a time in spawned worker processes set up as this
command's process is (``Worker``: threads, compile mode, where it may write, its log file and line prefix), or one
after the other in this process when ``jobs`` is 1. Every stage seeds itself (utils/seeding.py), so the numbers do
not depend on the order nor on the process a stage ran in. Used by `neurosym pipeline` (its stage graph) and by
the grid verbs (stages/jobs.py: `select`, `rl`).
"""

from __future__ import annotations

import dataclasses
import signal
import threading
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from multiprocessing import get_context
from typing import Any, Callable, Generator, Sequence

from ..config import RunConfig, UserError

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
    """A node of the graph: ``start()`` makes its flow once the nodes of ``needs`` (keys) are done; ``on_start``:
    called in this process as it starts."""

    key: str
    start: Callable[[], Flow]
    needs: tuple[str, ...] = ()
    on_start: Callable[[], None] | None = None


def one(job: Job) -> Flow:
    """The flow of a node that is one job: its result is the node's value."""
    (result,) = yield [job]
    return result


@dataclasses.dataclass(frozen=True)
class Worker:
    """How a worker process is set up: what commands/_run.py sets up in a command's own process. ``threads``: torch
    threads (0: torch's default); ``compile``, ``device``: the step's mode (utils/compiling.py); ``roots``: where it
    may write (utils/io.confine); ``log_file``, ``log_format``, ``log_datefmt``: the command's log file, appended to;
    ``prefix``: the command's own line prefix in a multirun, before each job's name; ``levels``: the log levels of
    the root and neurosym's loggers; ``quiet``: the console muted (the Python API's default)."""

    threads: int = 1
    compile: str = "auto"
    device: str = "cpu"
    roots: tuple[str, ...] = ()
    log_file: str = ""
    log_format: str = ""
    log_datefmt: str | None = None
    prefix: str = ""
    levels: tuple[tuple[str, int], ...] = ()
    quiet: bool = False

    @classmethod
    def like_this_process(cls, cfg: RunConfig, *, threads: int | None = None) -> "Worker":
        """A worker set up as this process is for ``cfg`` (``threads``: another thread count, the grids' one)."""
        import logging

        from ..utils.console import current_prefix
        from ..utils.io import confined

        files = [h for h in logging.getLogger().handlers if isinstance(h, logging.FileHandler)]
        fmt = files[0].formatter if files and files[0].formatter else None
        from ..utils.console import console, log

        return cls(cfg.threads if threads is None else threads, cfg.compile, cfg.device,
                   tuple(str(r) for r in confined()), files[0].baseFilename if files else "",
                   (fmt._fmt or "") if fmt else "", fmt.datefmt if fmt else None, current_prefix(),
                   (("", logging.getLogger().level), (log.name, log.level)), console.quiet)

    def __call__(self) -> None:
        """Set up this worker process (the pool's initializer)."""
        import logging
        import sys

        _die_with_parent()
        from ..utils.compiling import configure
        from ..utils.cpu import set_threads
        from ..utils.io import confine

        if self.threads:
            set_threads(self.threads)
        configure(self.compile, self.device)
        confine(list(self.roots))
        console = logging.StreamHandler(sys.stdout)  # a spawned process has no logging set up: its lines would be lost
        console.setFormatter(logging.Formatter("[%(asctime)s] %(levelname)s %(message)s", "%H:%M:%S"))
        handlers: list[logging.Handler] = [console]
        if self.log_file:
            to_file = logging.FileHandler(self.log_file, mode="a")
            to_file.setFormatter(logging.Formatter(self.log_format or None, self.log_datefmt))
            handlers.append(to_file)
        root = logging.getLogger()
        root.handlers[:] = handlers
        root.setLevel(logging.INFO)
        for name, level in self.levels:  # what this command's console shows (other libraries from WARNING)
            logging.getLogger(name or None).setLevel(level)
        from ..utils.console import console

        console.quiet = self.quiet


def _die_with_parent() -> None:
    """Ask Linux to end this worker when the process that started it ends (killed, or a SIGTERM it did not catch):
    its stage must not go on unseen holding its run directory's lock. Elsewhere: nothing."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def _call(fn: Callable[..., Any], args: tuple, name: str, prefix: str) -> Any:
    """A job inside a worker: its log lines name it (after the command's own prefix)."""
    from ..utils.console import set_job_prefix

    import pickle

    set_job_prefix(f"{prefix} {name}" if prefix else name)
    try:
        return fn(*args)
    except UserError as e:  # its one line must reach the command's process, whatever class carries it
        try:
            pickle.dumps(e)
        except Exception:
            raise UserError(str(e)) from None
        raise
    finally:
        set_job_prefix("")


def _script_hint() -> str:
    """What to say when workers die at once under a Python script: each imports the script again (spawn), and a
    script that starts its work at the top level fails there."""
    import sys

    main = getattr(sys.modules.get("__main__"), "__file__", "") or ""
    if not main or main.endswith(("neurosym", "neurosym.exe", "pytest", "cli.py", "__main__.py")):
        return ""
    return (f"; called from {main}: keep the script's work under `if __name__ == \"__main__\":` (each worker "
            "imports the script again), or pass pipeline.jobs=1")


class _Running:
    """A started node: its flow, the batch it waits for, the results of that batch so far."""

    def __init__(self, node: Node, flow: Flow) -> None:
        self.node, self.flow, self.results, self.waiting = node, flow, [], 0


def run_flow(nodes: Sequence[Node], jobs: int, *, worker: Worker | None = None,
             on_result: Callable[[Any], None] | None = None) -> dict[str, Any]:
    """Run every node's flow in dependency order, ``jobs`` jobs at a time in workers set up by ``worker`` (1: in
    this process, one node at a time, in the nodes' order as far as their waits allow); returns each node's value
    by key. ``on_result``: called in this process with every job's result as it comes (an exception it raises stops
    the flow). An error anywhere stops the flow: the workers are ended (what each stage finished is on disk, and a
    rerun resumes it) and the error is raised here."""
    keys = {n.key for n in nodes}
    missing = sorted({k for n in nodes for k in n.needs} - keys)
    if missing:
        raise ValueError(f"flow: nodes need unknown keys {missing}")
    todo, done, running = list(nodes), {}, {}
    queue: list[tuple[_Running, int, Job]] = []  # jobs ready to start, in order
    futures: dict[Future, tuple[_Running, int]] = {}
    worker = worker or Worker()
    pool = ProcessPoolExecutor(jobs, mp_context=get_context("spawn"), initializer=worker) if jobs > 1 else None

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
        while (len(futures) + len(queue) < jobs) if pool is not None else not running:
            node = next((n for n in todo if all(k in done for k in n.needs)), None)
            if node is None:
                return
            todo.remove(node)
            if node.on_start:
                node.on_start()
            r = running[node.key] = _Running(node, node.start())
            advance(r, None)

    def submit() -> None:
        while queue and (pool is not None and len(futures) < jobs or pool is None and not futures):
            r, i, job = queue.pop(0)
            if pool is None:
                f: Future = Future()
                try:
                    f.set_result(job.fn(*job.args))
                except BaseException as e:  # noqa: BLE001 - raised where the result is read, as a worker's would be
                    f.set_exception(e)
            else:  # a worker started now inherits Ctrl-C ignored: this process handles it and ends the workers
                main = threading.current_thread() is threading.main_thread()  # signals are the main thread's
                sigint = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
                try:
                    f = pool.submit(_call, job.fn, job.args, job.name, worker.prefix)
                finally:
                    if main:
                        signal.signal(signal.SIGINT, sigint)
            futures[f] = (r, i)

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
                    raise UserError(f"a worker process died ({e}); what finished is on disk, rerun the same command "
                                    f"to resume{_script_hint()}") from None
                if on_result is not None:
                    on_result(result)
                r.results[i] = result
                r.waiting -= 1
                if r.waiting == 0:
                    advance(r, r.results)
    except BaseException:
        if pool is not None:  # end the jobs still running: each resumes from its checkpoint on a rerun
            for p in list((getattr(pool, "_processes", None) or {}).values()):
                p.terminate()
            pool.shutdown(wait=False, cancel_futures=True)
            pool = None
        raise
    finally:
        if pool is not None:
            pool.shutdown()
    return done
