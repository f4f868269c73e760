"""Console output: one rich Console, progress that degrades to plain log lines, metric tables."""

from __future__ import annotations

import logging
import time
from typing import Mapping, Sequence

import rich
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

console = rich.get_console()  # shared with Hydra's RichHandler, so log lines print cleanly above a live bar
if not console.is_terminal:
    # pipes and CI: no 80-column wrapping of log lines (rich's default width without a terminal)
    rich.reconfigure(width=200)
log = logging.getLogger("neurosym")


def use_rich(mode: str, multirun: bool) -> bool:
    """Rich live display only on a terminal and outside multiruns (parallel bars would overwrite each other)."""
    if mode == "rich":
        return True
    if mode == "plain":
        return False
    return console.is_terminal and not multirun


class ProgressReporter:
    """Shows training progress: a rich bar with the loss, or a plain line every ``log_every`` steps."""

    def __init__(self, label: str, rich: bool, log_every: int):
        self.label, self.rich, self.log_every = label, rich, log_every
        self.progress: Progress | None = None
        self.task = None
        self.t0 = time.perf_counter()

    def __enter__(self) -> "ProgressReporter":
        if self.rich:
            self.progress = Progress(
                TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                TextColumn("{task.fields[info]}"), TimeElapsedColumn(), TimeRemainingColumn(), console=console,
            )
            self.progress.start()
        return self

    def __exit__(self, *exc) -> None:
        if self.progress is not None:
            self.progress.stop()

    def update(self, step: int, total: int, metrics: Mapping[str, float]) -> None:
        info = "  ".join(f"{k} {_fmt(v)}" for k, v in metrics.items() if k in ("rollouts", "loss", "grad_norm"))
        if self.progress is not None:
            if self.task is None:
                self.task = self.progress.add_task(self.label, total=total, completed=step - 1, info="")
            self.progress.update(self.task, completed=step, info=info)
        elif step % self.log_every == 0 or step == total or step == 1:
            log.info("%s step %d/%d  %s  (%.0f s)", self.label, step, total, info, time.perf_counter() - self.t0)


def _fmt(v: float) -> str:
    if isinstance(v, int) or float(v).is_integer():
        return f"{int(v)}"
    return f"{v:.4g}"


def metrics_table(title: str, rows: Sequence[tuple[str, Mapping[str, Mapping[str, float]]]], columns: Sequence[tuple[str, str]]) -> Table:
    """rows: (label, summary) with summary[metric] = {mean, std}; columns: (metric key, header)."""
    table = Table(title=title, header_style="bold")
    table.add_column("baseline")
    for _, header in columns:
        table.add_column(header, justify="right")
    for label, summary in rows:
        table.add_row(label, *(
            f"{summary[m]['mean']:.3f} ± {summary[m]['std']:.3f}" if m in summary else "-" for m, _ in columns
        ))
    return table


class SearchDisplay:
    """Live view of an MCMC search: step, best objective split into its terms, acceptance per move type,
    proposals/s. A rich live table on a terminal; a plain line every ~10% of the steps otherwise."""

    def __init__(self, label: str, total: int, lam: float, rich: bool):
        self.label, self.total, self.lam, self.rich = label, total, lam, rich
        self.live = None
        self.last = 0.0

    def __enter__(self) -> "SearchDisplay":
        if self.rich:
            from rich.live import Live

            self.live = Live(console=console, refresh_per_second=4, transient=False)
            self.live.start()
        return self

    def __exit__(self, *exc) -> None:
        if self.live is not None:
            self.live.stop()

    def _table(self, step: int, result, row) -> Table:
        t = Table(title=f"{self.label}: step {step}/{self.total} ({row['phase']})", show_header=True,
                  header_style="bold")
        t.add_column("best objective")
        t.add_column("= L1 action error")
        t.add_column(f"+ {self.lam:g} x degree")
        t.add_column("proposals/s", justify="right")
        b = result.best_score
        t.add_row(f"{b.total:.4f}", f"{b.l1:.4f}", f"{self.lam * b.degree:.4f} ({b.degree:.2f})",
                  f"{result.proposals_per_second:.0f}")
        acc = "  ".join(f"{m} {100 * a:.0f}%" for m, a in result.acceptance().items())
        t.caption = f"acceptance: {acc}"
        return t

    def update(self, step: int, result, row) -> None:
        now = time.perf_counter()
        if self.live is not None:
            if now - self.last > 0.25 or step == self.total:
                self.live.update(self._table(step, result, row))
                self.last = now
        elif step == 1 or step == self.total or step % max(1, self.total // 10) == 0:
            b = result.best_score
            acc = " ".join(f"{m}={100 * a:.0f}%" for m, a in result.acceptance().items())
            log.info("%s step %d/%d best %.4f = L1 %.4f + %g x degree %.3f | %.0f proposals/s | accept %s",
                     self.label, step, self.total, b.total, b.l1, self.lam, b.degree,
                     result.proposals_per_second, acc)
