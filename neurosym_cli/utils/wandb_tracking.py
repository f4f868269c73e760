"""logger=wandb: one Weights & Biases run per tracked run (utils/tracking.TrackedRun): its config, every step's
metrics (each group, train/ or search/, against its own step), its summary and its files.

Offline unless an API key is set (WANDB_API_KEY, or `wandb login`'s entry in ~/.netrc); WANDB_MODE overrides. The
runs lie in <runs_root>/wandb/; `wandb sync <runs_root>/wandb/offline-run-*` uploads offline
ones later. The project is WANDB_PROJECT's, else "neurosym"; the runs of one baseline's stages share a group
(<task dir>/<budget>/seed<S>/<baseline>), each stage its job type. A resumed training continues its run (the id
of each key is kept in <runs_root>/wandb/ids/); a run that starts over is a new run."""

from __future__ import annotations

import hashlib
import os
import secrets
import shutil
from pathlib import Path
from typing import Mapping

from ..errors import UserError, cut
from .tracking import TrackedRun, Tracker, missing

STORE, IDS = "wandb", "ids"
"""the runs' folder under the runs root (W&B's own name for it), and the folder of each key's run id there"""
PROJECT = "neurosym"
"""the project of every run unless WANDB_PROJECT names another"""


def _mode() -> str:
    """WANDB_MODE when set; else online with an API key (the variable or a ~/.netrc entry), offline without."""
    if os.environ.get("WANDB_MODE", "").strip():
        return os.environ["WANDB_MODE"].strip()
    if os.environ.get("WANDB_API_KEY", "").strip():
        return "online"
    import netrc
    from urllib.parse import urlparse

    host = urlparse(os.environ.get("WANDB_BASE_URL") or "https://api.wandb.ai").hostname or "api.wandb.ai"
    try:
        return "online" if netrc.netrc().authenticators(host) else "offline"
    except (OSError, netrc.NetrcParseError):
        return "offline"


class WandbTracker(Tracker):
    """One W&B run, started (or resumed) at construction."""

    def __init__(self, run: TrackedRun):
        try:
            import wandb
        except ImportError:
            raise missing("wandb") from None
        from .io import check_inside, write_text

        root = Path(run.store).resolve()
        check_inside(root)
        ids = root / STORE / IDS
        id_file = ids / f"{hashlib.sha1(run.key.encode()).hexdigest()[:20]}.txt"  # "<id> <key>"
        old = id_file.read_text().split(" ", 1)[0] if run.start and id_file.is_file() else ""
        ident = old or secrets.token_hex(6)  # a new run: W&B takes letters and digits
        t = run.tags
        try:
            self.run = wandb.init(
                mode=_mode(), dir=str(root), project=os.environ.get("WANDB_PROJECT") or PROJECT, id=ident,
                resume="allow" if old else None, name=run.key, job_type=t.get("stage"),
                group=run.group,
                tags=[v[:64] for v in t.values()], config={**run.params, **{f"neurosym.{k}": v for k, v in t.items()}},
                settings=wandb.Settings(silent=True, console="off", disable_git=True, x_disable_stats=True,
                                        save_code=False))
        except Exception as e:  # no network in online mode, a bad key, a folder it cannot write: one line
            said = str(e).strip().splitlines()
            raise UserError(f"logger=wandb could not start a run: {cut(said[0] if said else type(e).__name__, 300)}"
                            " (WANDB_MODE=offline keeps it on this machine)") from None
        if not old:
            ids.mkdir(parents=True, exist_ok=True)
            write_text(id_file, f"{ident} {run.key}\n")
        self.axes: set[str] = set()

    def log(self, step: int, metrics: Mapping[str, float]) -> None:
        row = {k: float(v) for k, v in metrics.items()}
        for name in metrics:  # each group (train/, search/, search/round2/) against its own step: <group>/step
            group = name.rsplit("/", 1)[0] if "/" in name else "metrics"
            if group not in self.axes:
                self.axes.add(group)
                self.run.define_metric(f"{group}/*", step_metric=f"{group}/step")
            row[f"{group}/step"] = step
        self.run.log(row)

    def summary(self, metrics: Mapping[str, float]) -> None:
        self.run.summary.update({k: float(v) for k, v in metrics.items()})

    def artifact(self, path: Path, folder: str = "") -> None:
        """A copy in the run's files folder, which W&B uploads with the run (at its end, or by `wandb sync`)."""
        dest = Path(self.run.dir) / folder / path.name
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, dest)
        self.run.save(str(dest), base_path=self.run.dir, policy="end")

    def close(self, failed: bool = False) -> None:
        self.run.finish(exit_code=1 if failed else 0)
