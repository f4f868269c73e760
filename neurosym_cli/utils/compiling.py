"""The process's ``compile=`` mode (stdlib only): whether the one environment step (step.py) runs compiled.

``off`` is the eager step, bit for bit what every committed number was made with. ``on`` compiles the step with
torch.compile (inductor) once per bucket shape; where compilation fails, or no C++ compiler is found, one line says
so and the eager step runs. ``fused`` is the eager step with a dense round's pair work (edge keys, logits, edge
messages and their gradients) in hand-fused numba kernels (policy/edge_kernels.py), on a CPU; elsewhere, or
without numba, one line says so and the eager step runs. ``auto`` is the eager step on a CPU and on a GPU: the
compiled step was slower in training and compiles for minutes, and the fused one, faster (1.8x training a dense
200-agent swarm, 3-9 % at the paper's sizes), does not give eager's numbers bit for bit, which every committed number and the README need (docs/performance.md, 'The
compiled step'). Every artifact's ``runtime`` records the mode asked for and the one in effect.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import sys
from pathlib import Path

CHOICES = {"auto": "the eager step where compiling was not measured faster (today: everywhere)",
           "on": "the step compiled by torch.compile (inductor), eager where it cannot compile",
           "fused": "the eager step with a dense round's pair work in hand-fused CPU kernels (numba) from 16 agents "
                    "on: 1.3x training random-cross, more for larger dense teams",
           "off": "the eager step (every committed number)"}
"""compile values -> what they do"""

_state: dict[str, object] = {"asked": "off", "on": False, "fused": False, "why": None, "seconds": 0.0, "shapes": 0}


def check(value: str) -> str | None:
    """A one-line error for an unknown compile value, else None."""
    if value in CHOICES:
        return None
    return f"unknown compile {value!r}; choose one of: " + ", ".join(f"{k} ({v})" for k, v in CHOICES.items())


def resolve(mode: str, device: str = "cpu") -> bool:
    """Whether ``mode`` compiles the step on ``device`` ('cpu', 'cuda', ...): ``auto`` never does today, as
    measured (module docstring)."""
    return mode == "on"


def cache_dir() -> Path:
    """Where inductor keeps compiled kernels across processes: $TORCHINDUCTOR_CACHE_DIR, else the user's cache
    directory ($XDG_CACHE_HOME or ~/.cache)/neurosym/inductor."""
    if os.environ.get("TORCHINDUCTOR_CACHE_DIR"):
        return Path(os.environ["TORCHINDUCTOR_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "neurosym" / "inductor"


def compiler() -> str | None:
    """The C++ compiler inductor would call on a CPU ($CXX, else c++, g++ or clang++), or None."""
    for name in filter(None, (os.environ.get("CXX"), "c++", "g++", "clang++")):
        if shutil.which(name):
            return name
    return None


def configure(mode: str, device: str = "cpu") -> bool:
    """Put ``compile=mode`` in effect for this process on ``device``; returns whether the step compiles. Without a
    C++ compiler (a CPU device) one line says so and the eager step runs; so does ``fused`` off a CPU or without
    numba (the fused kernels then never run: policy/edge_kernels.py ``serves``)."""
    on = resolve(mode, device)
    _state.update(asked=mode, on=on, fused=mode == "fused", why=None)
    if mode == "fused":
        return _configure_fused(device)
    if on and not str(device).startswith("cuda") and compiler() is None:
        fall_back("no C++ compiler was found (set CXX, or install g++)")
        return False
    if on:
        os.environ.setdefault("TORCHINDUCTOR_CACHE_DIR", str(cache_dir()))
    return on


def _configure_fused(device: str) -> bool:
    """compile=fused on ``device``: the fused kernels need a CPU and numba; else one line and the eager step."""
    from .device import resolve_device

    where = resolve_device(str(device)).type
    if where != "cpu":
        fall_back(f"the fused kernels run on a CPU, and this run is on {where}")
    elif importlib.util.find_spec("numba") is None:
        fall_back("numba is not installed (pip install numba)")
    else:
        try:  # installed is not importable (a numpy it does not support, ...)
            import numba  # noqa: F401
        except Exception as e:
            fall_back(f"numba cannot be imported ({type(e).__name__}: {str(e).strip()[:160]})")
    return False


def fused() -> bool:
    """Whether a dense round's pair work runs in the fused kernels now (compile=fused in effect)."""
    return bool(_state["fused"])


def enabled() -> bool:
    """Whether the step compiles now (compile=on and nothing has failed)."""
    return bool(_state["on"])


def fall_back(why: str) -> None:
    """Compilation cannot be used in this process: the eager step runs from here on, said in one line."""
    if _state["on"] or _state["fused"] or _state["why"] is None:
        print(f"neurosym: warning: compile={_state['asked']}: {why}; the eager step runs (compile=off)",
              file=sys.stderr)
    _state.update(on=False, fused=False, why=why)


def compiled(seconds: float, shapes: int = 1) -> None:
    """Count ``shapes`` bucket shapes compiled, taking ``seconds`` (the first call, compilation included); the fused
    kernels count their compilation (or load from numba's cache) as seconds of no shape."""
    _state["seconds"] = float(_state["seconds"]) + seconds  # type: ignore[arg-type]
    _state["shapes"] = int(_state["shapes"]) + shapes  # type: ignore[call-overload]


def in_effect() -> str:
    """The mode in effect: 'on' (compiled), 'fused' (the fused kernels) or 'off' (the eager step)."""
    return "on" if _state["on"] else "fused" if _state["fused"] else "off"


def record() -> dict[str, object]:
    """The compile mode as recorded in every artifact's runtime: asked, in effect, why not, and the compile cost."""
    return {"asked": _state["asked"], "in_effect": in_effect(), "why_off": _state["why"],
            "compile_seconds": round(float(_state["seconds"]), 3), "shapes_compiled": _state["shapes"]}  # type: ignore[arg-type]
