"""The policy's file formats (export.formats, verb_config.POLICY_FORMATS): what each writes, with which exporter,
and what it needs beyond torch.

    torchscript   policy.pt     torch.jit.trace of the team (deprecated upstream; what most robot stacks load)
    pt2           policy.pt2    torch.export.export of the team, saved by torch.export.save: B and N free, K within
                                policy.k_bounds
    onnx          policy.onnx   the team, and agent/*.onnx, the per-agent pieces; by the dynamo exporter
                                (export.onnx=dynamo, opset 18, needs onnxscript) or the legacy TorchScript-based one
                                (export.onnx=legacy, opset 17)

A format that cannot be written (its package missing, its exporter failing) leaves none of its files and says why
in one line, naming what to install; the others are written regardless (stages/export.py decides whether that
fails the command).
"""

from __future__ import annotations

import contextlib
import importlib
import io
import logging
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import torch

from ..utils.io import atomic_write_bytes
from ..verb_config import POLICY_FORMATS
from .policy import Graph

LEGACY_OPSET = 17
"""ONNX opset of the legacy exporter's graphs (onnxruntime >= 1.14 runs it)"""
DYNAMO_OPSET = 18
"""ONNX opset of the dynamo exporter's graphs, its lowest (onnxruntime >= 1.14 runs it)"""
ONNX_EXTRA = 'pip install -e ".[onnx]" (or pip install onnx onnxscript onnxruntime)'
"""how to install what the ONNX files need"""


@contextlib.contextmanager
def _quiet():
    """The exporters' expected notes (the tracer's shape warnings, torchvision absent, deprecation) silenced."""
    log = logging.getLogger("torch.onnx")
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield
    finally:
        log.setLevel(level)


def _dims(g: Graph) -> tuple:
    """torch.export's dynamic_shapes of ``g``'s inputs: one Dim per free size name, bounded by ``g.bounds``."""
    from torch.export import Dim

    names = dict.fromkeys(a for axes in g.inputs.values() for a in axes if a)
    dims = {a: Dim(a, min=g.bounds.get(a, (None, None))[0], max=g.bounds.get(a, (None, None))[1]) for a in names}
    return tuple({i: dims[a] for i, a in enumerate(axes) if a} for axes in g.inputs.values())


def _free(g: Graph) -> str:
    """The free sizes of ``g`` in words: 'B, N, K in [1, 15]'."""
    names = dict.fromkeys(a for axes in g.inputs.values() for a in axes if a)
    words = []
    for a in names:
        lo, hi = g.bounds.get(a, (None, None))
        words.append(a if lo is None else f"{a} in [{lo}, {hi}]" if hi is not None else f"{a} >= {lo}")
    return ", ".join(words)


def _torchscript(team: Graph, pieces: list[Graph], folder: Path, onnx: str) -> tuple[list[str], dict]:
    with _quiet(), torch.no_grad():
        traced = torch.jit.trace(team.module, team.args, check_trace=False)
        buf = io.BytesIO()
        torch.jit.save(traced, buf)
    atomic_write_bytes(folder / f"{team.file}.pt", buf.getvalue())
    return [f"{team.file}.pt"], {"exporter": f"torch.jit.trace, torch {torch.__version__}",
                                 "free": "B, N, K (traced: the softmax form is fixed at the traced K)"}


def _pt2(team: Graph, pieces: list[Graph], folder: Path, onnx: str) -> tuple[list[str], dict]:
    with _quiet():
        ep = torch.export.export(team.module, team.args, dynamic_shapes=_dims(team), strict=False)
        buf = io.BytesIO()
        torch.export.save(ep, buf)
    atomic_write_bytes(folder / f"{team.file}.pt2", buf.getvalue())
    return [f"{team.file}.pt2"], {"exporter": f"torch.export.export, torch {torch.__version__}",
                                  "free": _free(team)}


def _onnx_file(g: Graph, folder: Path, onnx: str) -> None:
    names, outs = list(g.inputs), list(g.outputs)
    with _quiet():
        if onnx == "dynamo":
            prog = torch.onnx.export(g.module, g.args, dynamo=True, dynamic_shapes=_dims(g), input_names=names,
                                     output_names=outs, opset_version=DYNAMO_OPSET, verbose=False)
            data = prog.model_proto.SerializeToString()
        else:
            axes = {name: {i: a for i, a in enumerate(ax) if a} for name, ax in {**g.inputs, **g.outputs}.items()}
            buf = io.BytesIO()
            torch.onnx.export(g.module, g.args, buf, dynamo=False, opset_version=LEGACY_OPSET, input_names=names,
                              output_names=outs, dynamic_axes=axes)
            data = buf.getvalue()
    atomic_write_bytes(folder / f"{g.file}.onnx", data)


def _onnx(team: Graph, pieces: list[Graph], folder: Path, onnx: str) -> tuple[list[str], dict]:
    for g in (team, *pieces):
        _onnx_file(g, folder, onnx)
    if onnx == "dynamo":
        words = (f"torch.onnx.export(dynamo=True), torch {torch.__version__}, onnxscript "
                 f"{importlib.import_module('onnxscript').__version__}")
    else:
        words = f"torch.onnx.export(dynamo=False), the legacy TorchScript-based exporter, torch {torch.__version__}"
    return [f"{g.file}.onnx" for g in (team, *pieces)], {
        "exporter": words, "opset": DYNAMO_OPSET if onnx == "dynamo" else LEGACY_OPSET,
        "free": _free(team) if onnx == "dynamo" else "B, N, K (traced: the softmax form is fixed at the traced K)"}


@dataclass(frozen=True)
class Format:
    """One policy format: the files it writes (globs, relative to the folder), the packages it needs beyond torch
    (by the ONNX exporter chosen), and its writer (team, pieces, folder, onnx exporter) -> (files, what made them)."""

    files: tuple[str, ...]
    needs: Callable[[str], tuple[str, ...]]
    write: Callable[[Graph, list[Graph], Path, str], tuple[list[str], dict]]


FORMATS: dict[str, Format] = {
    "torchscript": Format(("policy.pt",), lambda onnx: (), _torchscript),
    "pt2": Format(("policy.pt2",), lambda onnx: (), _pt2),
    "onnx": Format(("policy.onnx", "agent/*.onnx"),
                   lambda onnx: ("onnx", "onnxscript") if onnx == "dynamo" else ("onnx",), _onnx),
}
assert tuple(FORMATS) == POLICY_FORMATS, "one writer per format export.formats names"


def missing(fmt: str, onnx: str) -> str | None:
    """Why ``fmt`` cannot be written here (a package it needs is not installed, with what to install), else None."""
    for pkg in FORMATS[fmt].needs(onnx):
        try:
            importlib.import_module(pkg)
        except ImportError:
            return f"{pkg} is not installed: {ONNX_EXTRA}"
    return None


def _remove(folder: Path, fmt: str) -> None:
    """Whatever ``fmt`` had written into ``folder`` before it failed (the folder keeps no half format)."""
    for pattern in FORMATS[fmt].files:
        for path in folder.glob(pattern):
            path.unlink()
    for sub in {Path(p).parent for p in FORMATS[fmt].files} - {Path(".")}:
        if (folder / sub).is_dir() and not any((folder / sub).iterdir()):
            (folder / sub).rmdir()


def write_formats(team: Graph, pieces: list[Graph], folder: Path, formats: list[str], onnx: str) -> dict:
    """Each of ``formats`` written into ``folder``: format -> {"files": [...], "exporter": what made them, "free":
    the free sizes, ("opset")}, or {"files": [], "skipped": why, in one line} for one that could not be."""
    out: dict = {}
    for fmt in formats:
        why = missing(fmt, onnx)
        if why is None:
            try:
                files, made = FORMATS[fmt].write(team, pieces, folder, onnx)
                out[fmt] = {"files": files, **made}
                continue
            except Exception as e:  # an exporter that fails costs its own format only
                _remove(folder, fmt)
                text = str(e).strip().splitlines()
                why = f"its exporter failed: {type(e).__name__}: {text[0][:240] if text else ''}"
        out[fmt] = {"files": [], "skipped": why}
    return out
