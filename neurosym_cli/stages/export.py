"""`neurosym export`: a baseline's program and policy as artifacts that run without neurosym (neurosym_cli/export/,
docs/deploy.md), into <exp_dir>/export/<baseline label>/; ``export.check=true`` replays that folder's golden
vectors through each artifact in a process that cannot import neurosym."""

from __future__ import annotations

import hashlib
import io
import os
import shutil
from pathlib import Path

from ..run import RunDir
from ..run.layout import EXPORT_MANIFEST
from ..config import ConfigError, RunConfig, UserError
from ..utils.console import log, say
from ..utils.io import write_json, write_text
from ..verb_config import POLICY_FORMATS
from . import RunInfo


def export_dir(cfg: RunConfig) -> Path:
    """Where the export of ``cfg.baseline`` goes: export.dir, else <exp_dir>/export/<baseline label>."""
    return Path(cfg.export.dir) if cfg.export.dir else RunDir(cfg).export_dir


def export(cfg: RunConfig, info: RunInfo | None = None) -> dict:
    """Write the export folder (or check it, with export.check=true); returns what was written or the check's
    report."""
    from ..export.folder import claim

    folder = export_dir(cfg)
    if cfg.export.check:
        return check(folder, cfg.export.tolerance, cfg.export.formats)
    claimed = claim(folder, overwrite=cfg.overwrite)  # only an export is ever replaced
    return write_export(cfg, folder, claimed)


def check(folder: Path, tolerance: float | None = None, required: list[str] = ()) -> dict:
    """The check's report, one line per artifact; UserError on a mismatch, or on a ``required`` policy format
    (export.formats) that is not in the folder or cannot run here."""
    from ..export.check import run_check

    if not folder.exists():
        raise UserError(f"no export at {folder}; `neurosym export` with the same settings writes it")
    report = run_check(folder, tolerance, required)
    for r in report["results"]:
        colour = {"ok": "green", "skipped": "yellow"}.get(r["status"], "red")
        say(f"  {r['file']:<14} [{colour}]{r['status']:<9}[/] {r['detail']}")
    if report["neurosym_importable"]:
        raise UserError("the check's process could import neurosym, so it proves nothing; report this as a bug")
    if report["first_mismatch"]:
        raise UserError(f"export check failed: {report['first_mismatch']}")
    say(f"[green]export check passed[/] ({folder}): in a process without neurosym, tolerance "
        f"{report['tolerance']:g}, episodes {', '.join(map(str, report['episodes']))}")
    return report


def _program_of(comm):
    """The provider's program, when it is one (through a link-failure wrapper), else None."""
    from ..policy.comm import ProgramComm, unwrap

    inner = unwrap(comm)
    return inner if isinstance(inner, ProgramComm) else None


def write_export(cfg: RunConfig, folder: Path, claimed: object = None) -> dict:
    """Build the export in a temporary sibling of ``folder`` and publish it there (``claimed``: what
    export.folder.claim saw at ``folder``)."""
    import numpy as np
    import torch

    from ..export import bandwidth, codegen, golden, spec
    from ..export.folder import FORMAT, publish
    from ..export.formats import write_formats
    from ..export.policy import policy_graphs
    from ..export.readme import readme
    from ..tasks import make_task
    from ..tasks.base import applied_action
    from ..utils.io import atomic_write_bytes
    from ..utils.seeding import seed_everything
    from ..run.models import baseline_comm, load_baseline

    seed_everything(cfg.seed)
    device = torch.device("cpu")  # golden vectors on the CPU: what a robot's runtime compares against
    has_model = RunDir(cfg).model_file.exists()
    if has_model or not cfg.program:
        policy, task, comm = load_baseline(cfg, device)
    else:  # program=FILE with no trained model: the program alone
        policy, task = None, make_task(cfg.task, cfg.horizon)
        comm = baseline_comm(cfg, task)
    prog_comm = _program_of(comm)
    program = prog_comm.program if prog_comm is not None else None
    if program is None and policy is None:
        raise ConfigError("nothing to export: no program and no trained model")
    if policy is None and cfg.export.formats:
        raise ConfigError(f"export.formats={list(cfg.export.formats)} names policy formats, but there is no trained "
                          f"model for {RunDir(cfg).label} (a program alone has no policy to write)")
    asked = list(cfg.export.formats or POLICY_FORMATS)
    formats: dict = {}
    vocab = prog_comm.fmap.vocab if prog_comm is not None else None
    tmp = folder.parent / f".{folder.name}.tmp-{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    files: list[str] = []
    try:
        if program is not None:
            from ..policy.comm import ProgramComm

            args = (program, vocab, cfg.task.name, cfg.features, task.obs_dim, task.pair_dim)
            write_json(tmp / "program.json", spec.program_json(*args))
            write_text(tmp / "program.py", codegen.python_module(*args))
            write_text(tmp / "program.h", codegen.c_header(*args))
            files += ["program.json", "program.py", "program.h"]
            rec_comm = ProgramComm(program, prog_comm.fmap)  # the program alone: link failure is not exported
        else:
            rec_comm = comm
        if policy is not None:
            meta, arrays = golden.record(task, policy, rec_comm, program, cfg.export.episodes, device)
        else:
            meta, arrays = golden.record_program(task, rec_comm, program, max(cfg.export.episodes, 8))
        buf = io.BytesIO()
        np.savez_compressed(buf, **arrays)
        atomic_write_bytes(tmp / "golden.npz", buf.getvalue())
        write_json(tmp / "golden.json", meta)
        files += ["golden.npz", "golden.json"]
        if policy is not None:  # traced on golden episode 0, its steps as the batch
            team, pieces = policy_graphs(policy, applied_action(task),
                                         *(torch.from_numpy(arrays[f"e0_{k}"]) for k in ("agent", "rel", "picks")))
            formats = write_formats(team, pieces, tmp, asked, cfg.export.onnx)
            files += [f for v in formats.values() for f in v["files"]]
        standalone = Path(__file__).resolve().parents[1] / "export" / "standalone"
        for name in ("check.py", "agent_runtime.py"):
            shutil.copyfile(standalone / name, tmp / name)
        files += ["check.py", "agent_runtime.py"]
        manifest = {
            "format": FORMAT, "task": cfg.task.name, "baseline": RunDir(cfg).label,
            "budget": cfg.budget.name, "seed": cfg.seed, "features": cfg.features, "rounds": task.rounds,
            "program": program is not None, "policy": policy is not None,
            "agent_dim": task.obs_dim, "pair_dim": task.pair_dim, "action_dim": task.action_dim,
            "formats": formats, "opset": formats.get("onnx", {}).get("opset"), "tolerance": cfg.export.tolerance,
            "semantics": spec.SEMANTICS if program is not None else None,
            "bandwidth": bandwidth.of_run(cfg, policy, arrays),  # bits per agent per step: golden and evaluated
            "files": sorted(files + [EXPORT_MANIFEST, "README.md"]),
            "sha256": {f: hashlib.sha256((tmp / f).read_bytes()).hexdigest() for f in sorted(files)},
        }  # sha256: the check refuses an artifact edited after the export, even one no golden decision notices
        write_json(tmp / EXPORT_MANIFEST, manifest)
        write_text(tmp / "README.md", readme(manifest, meta, program, vocab, cfg, task))
        publish(tmp, folder, claimed)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    label = RunDir(cfg).label
    if program is None:
        say(f"{label} has no program: exported the policy alone (whom to hear is an input; golden picks are the "
            f"agents it heard)")
    elif policy is None:
        say(f"no trained model for {label}: exported the program alone")
    say(f"[green]exported[/] {label} to {folder}: {', '.join(sorted(files))}")
    for fmt, made in formats.items():
        say(f"  {fmt:<11} " + (f"[yellow]not written[/]: {made['skipped']}" if "skipped" in made else
                              f"{', '.join(made['files'][:2])}{' ...' if len(made['files']) > 2 else ''} "
                              f"({made['exporter']})"))
    failed = [f for f in cfg.export.formats if "skipped" in formats[f]]
    if failed:  # a format asked for by name must be written; the others are kept
        raise UserError(f"export.formats names {failed[0]}, which was not written ({formats[failed[0]]['skipped']}); "
                        f"the rest is in {folder}: fix that and rerun with overwrite=true")
    say("check it in a process without neurosym: the same command with --check (or export.check=true)")
    log.info("golden episodes: %s", ", ".join(f"{m['episode']} (loss {m.get('loss', float('nan')):.4f})"
                                             for m in meta["episodes"]))
    return {"folder": str(folder), "files": sorted(files), "program": program is not None,
            "policy": policy is not None, "episodes": meta["episodes"], "formats": formats}
