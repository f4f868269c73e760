"""The end of a sweep (a Hydra multirun): one comparison table of every job, read from the job_result.json each
job wrote (``_run.py``), and a non-zero exit when any job failed. Registered as a Hydra callback in
conf/_common_.yaml, so it runs in the launching process whatever the launcher (basic, joblib, submitit)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig


def _num(name: str) -> int:
    head = name.split("_", 1)[0]
    return int(head) if head.isdigit() else 1 << 30


def collect(sweep_dir: Path) -> list[dict[str, Any]]:
    """One entry per job directory of the sweep, in job order; a job that wrote no result is marked so."""
    rows = []
    for d in sorted((p for p in sweep_dir.iterdir() if p.is_dir() and (p / ".hydra").is_dir()),
                    key=lambda p: _num(p.name)):
        try:
            rows.append(json.loads((d / "job_result.json").read_text()))
        except (OSError, ValueError):
            rows.append({"ok": False, "job": _num(d.name), "overrides": [],
                         "error": f"no result (it crashed or was killed; see {d})"})
    return rows


class SweepSummary(Callback):
    """Prints the sweep's comparison table and fails the command when a job failed."""

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
        t = Table(title=f"sweep of {config.get('cmd', '')}: {len(rows)} jobs ({sweep_dir})", header_style="bold")
        t.add_column("#", justify="right")
        t.add_column("job")
        for c in cols:
            t.add_column(c, justify="right")
        t.add_column("outcome")
        for r in rows:
            ov = [o for o in r.get("overrides", []) if not swept or o.split("=")[0].lstrip("+~") in swept]
            vals = [r.get("row", {}).get(c) for c in cols]
            t.add_row(str(r.get("job", "")), " ".join(ov) or "-",
                      *("-" if v is None else f"{v:.4g}" if isinstance(v, float) else str(v) for v in vals),
                      "[green]ok[/]" if r.get("ok") else f"[red]failed[/]: {r.get('error', '')}")
        console.print(t)
        failed = [r for r in rows if not r.get("ok")]
        if failed:
            console.print(f"[red]{len(failed)} of {len(rows)} jobs failed[/] (the others' results are in place)")
            raise SystemExit(1)
