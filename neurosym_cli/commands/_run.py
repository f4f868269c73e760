"""The wrapper every command runs in: typed config, threads, and one-line errors instead of tracebacks."""

from __future__ import annotations

import sys
from typing import Any, Callable

from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from ..config import RunConfig, UserError
from ..stages import RunInfo


def _error(name: str, msg: str, code: int = 1) -> None:
    print(f"neurosym {name.replace('_', '-')}: error: {msg}", file=sys.stderr)
    raise SystemExit(code)


def _plain_logs_off_terminal() -> None:
    """Off a terminal (CI, pipes, cluster logs) swap rich's log handler for plain timestamped lines."""
    import logging

    from rich.logging import RichHandler

    from ..utils.console import console

    if console.is_terminal:
        return
    root = logging.getLogger()
    for h in list(root.handlers):
        if isinstance(h, RichHandler):
            root.removeHandler(h)
            plain = logging.StreamHandler(sys.stdout)
            plain.setFormatter(logging.Formatter("[%(asctime)s] %(levelname)s %(message)s", "%H:%M:%S"))
            root.addHandler(plain)


def job_prefix(overrides: list[str], num: int) -> str:
    """What tells this sweep job from the others: the values of the swept keys (NEUROSYM_SWEPT, set by the
    console script), else the job's number."""
    import os

    swept = [k for k in os.environ.get("NEUROSYM_SWEPT", "").split(",") if k]
    picked = [o for o in overrides if o.partition("=")[0].lstrip("+~") in swept]
    return " ".join(picked) if picked else f"job {num}"


def run_command(name: str, cfg: DictConfig, fn: Callable[[RunConfig, RunInfo], Any]) -> Any:
    """Run a verb's ``run(typed config, run info)``; bad input and Ctrl-C end in one line, never a traceback."""
    try:
        typed: RunConfig = OmegaConf.to_object(cfg)  # type: ignore[assignment]
    except UserError as e:
        _error(name, str(e))
    except OmegaConfBaseException as e:
        _error(name, str(e).splitlines()[0])
    _plain_logs_off_terminal()
    hc = HydraConfig.get()
    if hc.mode == RunMode.MULTIRUN:  # parallel jobs' lines interleave: each names its own overrides
        from ..utils.console import set_job_prefix

        set_job_prefix(job_prefix(list(hc.overrides.task), hc.job.num))
    info = RunInfo(OmegaConf.to_container(cfg, resolve=True), hc.mode == RunMode.MULTIRUN,  # type: ignore[arg-type]
                   hc.runtime.output_dir)
    if typed.threads:
        import torch  # only here: show-program must not pay for importing torch

        torch.set_num_threads(typed.threads)
    try:
        return fn(typed, info)
    except UserError as e:
        _error(name, str(e))
    except KeyboardInterrupt:
        _error(name, "interrupted; artifacts written so far are intact, re-run the same command to resume", 130)
