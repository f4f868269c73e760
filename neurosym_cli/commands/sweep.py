"""The end of a sweep (a Hydra multirun): one comparison table of every job, read from the job_result.json each
job wrote (``_run.py``), and a non-zero exit when any job failed. Registered as a Hydra callback in
conf/_common_.yaml, so it runs in the launching process whatever the launcher (basic, joblib, submitit)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig


MARKER = ".neurosym-sweep"
"""<sweep dir>/.neurosym-sweep: the id of the sweep running there now (a later sweep may reuse the directory), stamped
by every job into its job_result.json; a result without this sweep's id is an earlier sweep's"""


def _num(name: str) -> int:
    head = name.split("_", 1)[0]
    return int(head) if head.isdigit() else 1 << 30


def start(sweep_dir: Path) -> str:
    """Mark ``sweep_dir`` as this sweep's and return its id (the launching process, before any job starts)."""
    import uuid

    from ..utils.io import write_text

    sweep_id = uuid.uuid4().hex
    write_text(sweep_dir / MARKER, sweep_id + "\n")
    return sweep_id


def sweep_id(sweep_dir: Path) -> str:
    """The id of the sweep running in ``sweep_dir`` ("" when none was marked: a sweep started by an older version)."""
    try:
        return (sweep_dir / MARKER).read_text().strip()
    except OSError:
        return ""


def job_sweep_id(job_dir: Path) -> str:
    """The id of the sweep a job directory belongs to: the marker of the nearest directory above it (a job's
    subdirectory may nest when an override's value has a '/')."""
    for d in Path(job_dir).parents:
        if (d / MARKER).is_file():
            return sweep_id(d)
    return ""


def _well_formed(r: Any) -> bool:
    """A job_result.json as ``_run.py`` writes it: anything else is a failed job, never a crash of the table."""
    return (isinstance(r, dict) and isinstance(r.get("ok"), bool) and isinstance(r.get("job"), int)
            and isinstance(r.get("overrides"), list) and all(isinstance(o, str) for o in r["overrides"])
            and isinstance(r.get("row", {}), dict) and isinstance(r.get("error", ""), str))


def collect(sweep_dir: Path) -> list[dict[str, Any]]:
    """One entry per job of the sweep marked in ``sweep_dir``, in job order. A job directory whose result carries
    another sweep's id (or none) is an earlier sweep's and left out, unless Hydra started it after this sweep was
    marked: then its result is missing or malformed (it crashed, was killed, or the file was damaged) and it failed."""
    current = sweep_id(sweep_dir)
    try:
        began = (sweep_dir / MARKER).stat().st_mtime
    except OSError:
        began = None
    rows = []
    # a job's directory nests when an override's value has a '/' (program=/path/p.txt): found wherever it is
    jobs = [h.parent for h in sweep_dir.rglob(".hydra") if h.is_dir()]
    for d in sorted(jobs, key=lambda p: _num(p.relative_to(sweep_dir).parts[0])):
        try:
            r = json.loads((d / "job_result.json").read_text())
        except (OSError, ValueError):
            r, why = None, f"no result (it crashed or was killed; see {d})"
        else:
            why = f"malformed {d / 'job_result.json'} (the job's outcome is unknown; run it again)"
        if _well_formed(r) and r.get("sweep", "") == current:
            rows.append(r)
            continue
        try:
            started = (d / ".hydra" / "overrides.yaml").stat().st_mtime
        except OSError:
            started = None
        if current and (began is None or started is None or started < began):
            continue  # an earlier sweep's job in a reused directory
        rows.append({"ok": False, "job": _num(d.relative_to(sweep_dir).parts[0]), "overrides": [], "error": why})
    return rows


def _cell(v: Any) -> str:
    """A table cell: floats with three decimals as every results table has them (413.806, never 414), the very
    large and very small in three significant digits."""
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.3f}" if v == 0 or 1e-3 <= abs(v) < 1e7 else f"{v:.3g}"
    return str(v)


class SweepSummary(Callback):
    """Marks the sweep directory, prints the sweep's comparison table and fails the command when a job failed."""

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        start(Path(str(config.hydra.sweep.dir)))

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        from rich.table import Table

        from ..utils.console import console

        sweep_dir = Path(str(config.hydra.sweep.dir))
        if not sweep_dir.is_dir():
            return
        rows = collect(sweep_dir)
        if not rows:
            return
        swept = [k for k in __import__("os").environ.get("NEUROSYM_SWEPT", "").split(",") if k]
        cols: list[str] = []
        for r in rows:
            cols += [c for c in r.get("row", {}) if c not in cols]
        from ..degrees import LEGEND, NAMES

        shows_degrees = any(c in NAMES.values() for c in cols)
        t = Table(title=f"sweep of {config.get('cmd', '')}: {len(rows)} jobs ({sweep_dir})", header_style="bold",
                  caption=LEGEND if shows_degrees else None, caption_justify="left")
        t.add_column("#", justify="right")
        t.add_column("job")
        for c in cols:
            t.add_column(c, justify="right")
        t.add_column("outcome")
        for r in rows:
            ov = [o for o in r.get("overrides", []) if not swept or o.split("=")[0].lstrip("+~") in swept]
            vals = [r.get("row", {}).get(c) for c in cols]
            t.add_row(str(r.get("job", "")), " ".join(ov) or "-",
                      *(_cell(v) for v in vals),
                      "[green]ok[/]" if r.get("ok") else f"[red]failed[/]: {r.get('error', '')}")
        console.print(t)
        failed = [r for r in rows if not r.get("ok")]
        if failed:
            console.print(f"[red]{len(failed)} of {len(rows)} jobs failed[/] (the others' results are in place)")
            raise SystemExit(1)
