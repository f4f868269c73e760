"""Console output: one rich Console, progress that degrades to plain log lines, metric tables."""

from __future__ import annotations

import logging
import time
from typing import Mapping, Sequence

import rich
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table
from rich.text import Text

console = rich.get_console()  # shared with Hydra's RichHandler, so log lines print cleanly above a live bar
if not console.is_terminal:
    # pipes and CI: no 80-column wrapping of log lines (rich's default width without a terminal)
    rich.reconfigure(width=200)
log = logging.getLogger("neurosym")

_job = {"prefix": ""}


def set_job_prefix(prefix: str) -> None:
    """Inside a multirun, every log line and final line of this job starts with ``[prefix]`` (its overrides), so
    the lines of parallel jobs can be told apart."""
    _job["prefix"] = prefix
    if prefix:
        for h in logging.getLogger().handlers:
            if not any(isinstance(f, _JobPrefix) for f in h.filters):
                h.addFilter(_JobPrefix())


class _JobPrefix(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        if _job["prefix"] and not getattr(record, "_job_prefixed", False):
            record.msg = f"[{_job['prefix'].replace('%', '%%')}] {record.msg}"
            record._job_prefixed = True  # one record can pass several handlers
        return True


def current_prefix() -> str:
    """This job's prefix in a multirun ("" outside one)."""
    return _job["prefix"]


def say(text: str) -> None:
    """A final line of a stage (done, synthesized, ...): on the console, with the job's prefix in a multirun."""
    from rich.markup import escape

    console.print(f"[dim]{escape('[' + _job['prefix'] + ']')}[/] {text}" if _job["prefix"] else text)


def use_rich(mode: str, multirun: bool) -> bool:
    """Rich live display only on a terminal and outside multiruns (parallel bars would overwrite each other)."""
    if mode == "rich":
        return True
    if mode == "plain":
        return False
    return console.is_terminal and not multirun


class Eta:
    """Time left of a loop of ``total`` steps, from the times its steps took. The steps up to ``start + warmup``
    are left out (the first one compiles kernels and fills caches: 10 times a later one is common), and the time
    per step is a running mean that weighs recent steps more (the n-th step measured weighs max(2 / (n + 1),
    ``floor``)): exact while the pace is steady after the warm-up, and following a pace that drifts (a search's
    final phase on the whole dataset, a machine that got busier). Steps may be reported one by one or in jumps."""

    def __init__(self, total: int, start: int = 0, warmup: int = 1, floor: float = 0.05, now: float | None = None):
        self.total, self.floor, self.warm_until = total, floor, start + warmup
        self.last = (start, time.perf_counter() if now is None else now)  # (step, perf_counter seconds)
        self.per_step: float | None = None  # seconds
        self.measured = 0  # steps measured (after the warm-up)

    def update(self, step: int, now: float | None = None) -> float | None:
        """Record that ``step`` steps are done at ``now`` (perf_counter seconds); returns the seconds left, None
        while nothing after the warm-up was measured."""
        now = time.perf_counter() if now is None else now
        last_step, last_time = self.last
        if step > last_step:
            self.last = (step, now)
            if last_step >= self.warm_until:  # an interval holding a warm-up step is never measured
                n = step - last_step
                x = (now - last_time) / n
                weight = 1 - (1 - max(2 / (self.measured + 2), self.floor)) ** n
                self.per_step = x if self.per_step is None else self.per_step + weight * (x - self.per_step)
                self.measured += n
        return self.left(step)

    def left(self, step: int) -> float | None:
        """Seconds left after ``step`` steps, or None before the pace is known."""
        return None if self.per_step is None else self.per_step * max(self.total - step, 0)


def left_text(seconds: float | None) -> str:
    """Time left as m:ss (or h:mm:ss), '?' while it is not known yet (the warm-up)."""
    return "?" if seconds is None else clock(seconds)


class Parts:
    """Progress of a phase made of a few named parts (the figures): one line as each begins, with its count, the
    time elapsed and, from the second part on, the time left at the mean pace of the parts done."""

    def __init__(self, label: str, total: int):
        self.label, self.total, self.done, self.t0 = label, total, 0, time.perf_counter()

    def begin(self, what: str) -> None:
        elapsed = time.perf_counter() - self.t0
        left = elapsed / self.done * (self.total - self.done) if self.done else None
        self.done += 1
        log.info("%s %d/%d: %s (%s elapsed, %s left)", self.label, self.done, self.total, what, clock(elapsed),
                 left_text(left))


class ProgressReporter:
    """Shows training progress: a rich bar with the loss, or a plain line every ``log_every`` steps; time left
    from ``Eta`` (warm-up left out)."""

    def __init__(self, label: str, rich: bool, log_every: int):
        self.label, self.rich, self.log_every = label, rich, log_every
        self.progress: Progress | None = None
        self.task = None
        self.t0 = time.perf_counter()
        self.eta: Eta | None = None

    def __enter__(self) -> "ProgressReporter":
        if self.rich:
            self.progress = Progress(
                TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(), TextColumn("steps"),
                TextColumn("{task.fields[info]}"), TextColumn("elapsed"), TimeElapsedColumn(),
                TextColumn("left {task.fields[left]}"), console=console,
            )
            self.progress.start()
        return self

    def __exit__(self, *exc) -> None:
        if self.progress is not None:
            self.progress.stop()

    def update(self, step: int, total: int, metrics: Mapping[str, float]) -> None:
        shown = {"rollouts": "rollouts", "loss": "loss", "degree": "max in+out", "grad_norm": "grad_norm"}
        info = "  ".join(f"{shown[k]} {_fmt(v)}" for k, v in metrics.items() if k in shown)
        if self.eta is None:  # a resumed run: time left is measured from the steps of this run
            self.eta = Eta(total, start=step - 1, now=self.t0)
        left = left_text(self.eta.update(step))
        if self.progress is not None:
            if self.task is None:
                self.task = self.progress.add_task(self.label, total=total, completed=step - 1, info="", left="?")
            self.progress.update(self.task, completed=step, info=info, left=left)
        elif step % self.log_every == 0 or step == total or step == 1:
            elapsed = time.perf_counter() - self.t0
            log.info("%s step %d/%d  %s  (%s elapsed, %s left)", self.label, step, total, info, clock(elapsed), left)


def clock(seconds: float) -> str:
    """Seconds as m:ss (or h:mm:ss)."""
    s = int(round(seconds))
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


def _fmt(v: float) -> str:
    if isinstance(v, int) or float(v).is_integer():
        return f"{int(v)}"
    return f"{v:.4g}"


def metrics_table(title: str, rows: Sequence[tuple[str, Mapping[str, Mapping[str, float]]]],
                  columns: Sequence[tuple[str, str]], err: str = "std", caption: str | None = None) -> Table:
    """rows: (label, summary) with summary[metric] = {mean, std, ...}; columns: (metric key, header); ``err``: the
    summary key printed after ± (the title says what it is); ``caption``: a line under the table (a legend)."""
    table = Table(title=title, header_style="bold", caption=caption, caption_justify="left")
    table.add_column("baseline")
    for _, header in columns:
        table.add_column(header, justify="right")
    for label, summary in rows:
        table.add_row(label, *(
            f"{summary[m]['mean']:.3f} ± {summary[m][err]:.3f}" if m in summary else "-" for m, _ in columns
        ))
    return table


class SearchDisplay:
    """Live view of an MCMC search: a bar with time left, then the best program's objective split into its terms,
    acceptance per move type and proposals/s, in labelled columns; a closing summary line. A rich live view on a
    terminal; a plain line every ~10% of the steps otherwise."""

    def __init__(self, label: str, total: int, lam: float, rich: bool, moves: Mapping[str, str] | None = None,
                 objective: str = "paper"):
        from ..degrees import objective_legend, objective_term

        self.label, self.total, self.lam, self.rich = label, total, lam, rich
        self.term, self.legend = objective_term(objective), objective_legend(objective)  # the degree term's word
        self.moves = dict(moves or {})  # move name -> what it changes, explained under the table
        self.live = None
        self.progress: Progress | None = None
        self.task = None
        self.last = 0.0
        self.t0 = time.perf_counter()
        self.eta = Eta(total, now=self.t0)  # the first step compiles the scorer's kernels and fills its caches

    def __enter__(self) -> "SearchDisplay":
        if self.rich:
            from rich.live import Live

            self.progress = Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                                     TextColumn("steps ({task.fields[phase]})  elapsed"), TimeElapsedColumn(),
                                     TextColumn("left {task.fields[left]}"), console=console)
            self.task = self.progress.add_task(self.label, total=self.total, phase="", left="?")
            self.live = Live(console=console, refresh_per_second=4, transient=False)
            self.live.start()
        return self

    def __exit__(self, *exc) -> None:
        if self.live is not None:
            self.live.stop()
            if not console.is_terminal:  # forced rich into a file: end the last frame's line
                console.line()

    def _view(self, step: int, result, row):
        from rich.console import Group

        assert self.progress is not None
        self.progress.update(self.task, completed=step, phase=row["phase"], left=left_text(self.eta.left(step)))
        t = Table(show_header=True, header_style="bold", title="best program so far", title_justify="left")
        t.add_column("objective", justify="right")
        t.add_column("= L1 action error", justify="right")
        t.add_column(f"+ {self.lam:g} x {self.term}", justify="right")
        t.add_column(self.term, justify="right")
        t.add_column("proposals/s", justify="right")
        b = result.best_score
        t.add_row(f"{b.total:.4f}", f"{b.l1:.4f}", f"{self.lam * b.degree:.4f}", f"{b.degree:.3f}",
                  f"{result.proposals_per_second:.0f}")
        acc = "  ".join(f"{m} {100 * a:.0f}%" for m, a in result.acceptance().items())
        parts = [self.progress, t, Text(self.legend, style="dim"), Text(f"accepted proposals per move: {acc}")]
        if self.moves:
            parts.append(Text("moves: " + "; ".join(f"{m} = {d}" for m, d in self.moves.items()), style="dim"))
        return Group(*parts)

    def update(self, step: int, result, row) -> None:
        now = time.perf_counter()
        self.eta.update(step, now)
        if self.live is not None:
            if now - self.last > 0.25 or step == self.total:
                self.live.update(self._view(step, result, row))
                self.last = now
        elif step == 1 or step == self.total or step % max(1, self.total // 10) == 0:
            b = result.best_score
            acc = " ".join(f"{m}={100 * a:.0f}%" for m, a in result.acceptance().items())
            elapsed = now - self.t0
            log.info("%s step %d/%d (%s elapsed, %s left)  best objective %.4f = L1 %.4f + %g x %s %.3f"
                     "  |  %.0f proposals/s  |  accepted per move: %s", self.label, step, self.total,
                     clock(elapsed), left_text(self.eta.left(step)), b.total, b.l1, self.lam,
                     self.term, b.degree, result.proposals_per_second, acc)

    def summary(self, result) -> None:
        """One closing line: the best objective, its terms, and the search's cost."""
        b = result.best_score
        say(f"[green]search done[/] {self.label}: best objective {b.total:.4f} = L1 {b.l1:.4f} + {self.lam:g} x "
            f"{self.term} {b.degree:.3f}; {sum(result.proposed.values())} proposals in {clock(result.seconds)} "
            f"({result.proposals_per_second:.0f}/s; {self.legend})")
