"""The wrapper every command runs in: typed config, threads, and one-line errors instead of tracebacks."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, Callable

from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf, open_dict
from omegaconf.errors import OmegaConfBaseException

from ..config import RunConfig, UserError
from ..errors import ConfigError, cut_words, exit_status, resource_problem
from ..stages import RunInfo


def _error(name: str, msg: str, code: int = 1) -> None:
    print(f"neurosym {name.replace('_', '-')}: error: {cut_words(msg)}", file=sys.stderr)
    raise SystemExit(code)


def _problem(e: Exception) -> str | None:
    """The one line of a failure that is the input's or the machine's (bad input, a full or read-only disk, memory
    exhausted), None for a bug (its traceback is kept)."""
    return str(e) if isinstance(e, UserError) else resource_problem(e)


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


def _row(result: Any, objective: str = "paper") -> dict[str, Any]:
    """The numbers of a verb's result worth a column in a sweep's comparison table (``objective``: the search's
    synth.objective, which names a program's degree term)."""
    from ..degrees import objective_term

    if not isinstance(result, dict):
        return {}
    if isinstance(result.get("cost"), dict):  # eval: the summary of every metric
        return {k: result[m]["mean"] for k, m in (("loss", "cost"), ("max in", "max_in"), ("max out", "max_out"),
                                                     ("max in+out", "max_degree")) if isinstance(result.get(m), dict)}
    names = {"loss": "loss", "objective": "objective", "l1": "l1", "degree": f"{objective_term(objective)} on D",
             "frames": "frames"}
    keep = {names[k]: v for k, v in result.items() if k in names and isinstance(v, (int, float))}
    for k in ("program", "tree", "checkpoint", "selected"):  # where the job's artifact is: the sweep table shows it
        if isinstance(result.get(k), str):
            keep["artifact"] = result[k]
            break
    if all(":" in str(k) for k in result) and result:  # pipeline: one entry per stage
        keep["stages"] = len(result)
    return keep


def typed_config(cfg: DictConfig) -> RunConfig:
    """The typed config of a composed one: the task node merged into its class's schema first (tasks/registry.py),
    so its defaults fill the interpolations that read it (``rules: ${task.rules}``); errors are one line."""
    from ..tasks.registry import typed_task

    cfg = cfg.copy()
    with open_dict(cfg):
        cfg.task = typed_task(cfg.task)
    try:
        return OmegaConf.to_object(cfg)  # type: ignore[return-value]
    except OmegaConfBaseException as e:
        raise ConfigError(str(e).splitlines()[0]) from None  # a value of the wrong type: bad configuration


def _wrote_since(exp_dir: Path, logs: Path, started: float) -> bool:
    """Whether a file under ``exp_dir`` (its log directories aside) changed since ``started`` (time.time())."""
    import os

    for top, dirs, files in os.walk(exp_dir):
        dirs[:] = [d for d in dirs if Path(top, d) != logs.parent]
        for f in files:
            try:
                if os.stat(Path(top, f)).st_mtime >= started:
                    return True
            except OSError:
                continue
    return False


def _drop_log_dir(logs: Path, cfg: DictConfig, started: float) -> None:
    """A command that stopped on bad input before writing anything did nothing worth a record: its Hydra log
    directory goes, and with it the directories Hydra made for it that are empty now
    (``<task>/<budget>/seed<S>/logs``), up to the runs root. Its one-line error is the whole story. The logs of a
    command that wrote something before it stopped are kept."""
    import shutil

    from ..errors import lies_under

    root = Path(str(cfg.get("runs_root", "") or "")).expanduser().absolute()
    if not str(cfg.get("runs_root", "")) or not lies_under(logs, root) or logs.absolute() == root:
        return  # logs the user sent elsewhere (hydra.run.dir=...) are theirs
    if _wrote_since(Path(str(cfg.get("exp_dir", logs.parent.parent))), logs, started):
        return
    shutil.rmtree(logs, ignore_errors=True)
    for d in logs.absolute().parents:
        if d == root or not lies_under(d, root):
            break
        try:
            d.rmdir()  # only when empty
        except OSError:
            break


def run_header(name: str, cfg: RunConfig, sources: dict[str, str]) -> str:
    """A command's first log line: the task, budget and seed in effect (and where a persistent default came from,
    ``defaults.py``), and the run directory."""
    def where(key: str) -> str:
        return f" (from {sources[key]})" if key in sources else ""

    read = cfg.report_dir or cfg.report.seed_files  # report of another directory: the task and budget play no part
    if read:
        return f"neurosym {name.replace('_', '-')}: {read}"
    return (f"neurosym {name.replace('_', '-')}: task={cfg.task.name}{where('task')} budget={cfg.budget.name}"
            f"{where('budget')} seed={cfg.seed} -> {cfg.exp_dir}")


def run_command(name: str, cfg: DictConfig, fn: Callable[[RunConfig, RunInfo], Any]) -> Any:
    """Run a verb's ``run(typed config, run info)``; bad input and Ctrl-C end in one line, never a traceback.

    Inside a multirun a job's bad input fails that job alone: its line is printed, its outcome written to
    job_result.json in its Hydra directory, and the other jobs run; the sweep's summary (``sweep.py``) lists
    every job and exits non-zero when one failed."""
    import logging
    import time

    logging.raiseExceptions = False  # a log file on a full disk drops its line (the console has it), no traceback
    started = time.time() - 1.0  # file times can lag the clock by a tick
    hc = HydraConfig.get()
    sweep = hc.mode == RunMode.MULTIRUN
    _plain_logs_off_terminal()
    if sweep:  # parallel jobs' lines interleave: each names its own overrides
        from ..utils.console import set_job_prefix

        set_job_prefix(job_prefix(list(hc.overrides.task), hc.job.num))
    record = Path(hc.runtime.output_dir) / "job_result.json"
    overrides = list(hc.overrides.task)
    stamp: dict[str, Any] = {}
    if sweep:  # stamped with the sweep's id; written first, so a job killed mid-run reads as failed, not as stale
        from ..utils.io import confine, write_json
        from .sweep import job_sweep_id

        # jobs of one sweep share this process: the previous job's confinement (its own Hydra directory) must not
        # refuse this job's record when the sweep directory lies outside the runs root
        confine([hc.runtime.output_dir])
        stamp = {"job": hc.job.num, "overrides": overrides, "sweep": job_sweep_id(Path(hc.runtime.output_dir))}
        write_json(record, {"ok": False, **stamp,
                            "error": f"no result (it crashed or was killed; see {hc.runtime.output_dir})"})
    try:
        typed = typed_config(cfg)
        from ..utils.cpu import warn_once

        warn_once(typed.cpu_kernels)  # torch is loaded by now: one line if the config asks for other kernels
        info = RunInfo(sweep, hc.runtime.output_dir)
        from ..defaults import sources_in_effect
        from ..utils.console import log

        log.info(run_header(name, typed, sources_in_effect()))
        from ..utils.io import confine

        # the runs root, the output directories a user named, and Hydra's own (job_result.json; a read-only
        # command's logs in the temp directory)
        confine([typed.runs_root, hc.runtime.output_dir,
                 *(d for d in (typed.report_dir, typed.report.seed_files) if d)])
        if typed.selected and name not in ("select", "pipeline"):  # the pipeline selects first when it must
            from ..stages.select import apply_selected

            typed = apply_selected(typed)
        from ..stages.front_select import apply_front_pick

        typed = apply_front_pick(typed, name.replace("_", "-"))  # eval, render, ...: what the pipeline picked
        if typed.threads:
            from ..utils.cpu import set_threads

            set_threads(typed.threads)  # without importing torch: show-program and report must not pay for it
        from ..utils.compiling import configure

        configure(typed.compile, typed.device)  # the step compiled or eager (step.py), recorded in runtime
        result = fn(typed, info)
    except Exception as e:
        msg = _problem(e)
        if msg is None:
            raise
        if not sweep:
            _drop_log_dir(Path(hc.runtime.output_dir), cfg, started)
            _error(name, msg, exit_status(e))
        from ..utils.console import say
        from ..utils.io import write_json

        say(f"[red]neurosym {name.replace('_', '-')}: error:[/] {cut_words(msg)} (this job only; the sweep goes on)")
        write_json(record, {"ok": False, **stamp, "error": msg})
        return None
    except KeyboardInterrupt:
        _error(name, "interrupted; artifacts written so far are intact, re-run the same command to resume", 130)
    if sweep:
        from ..utils.io import write_json

        write_json(record, {"ok": True, **stamp, "row": _row(result, typed.synth.objective)})
    return result
