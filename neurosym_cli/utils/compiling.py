"""The process's ``compile=`` mode (stdlib only): whether the one environment step (step.py) runs compiled.

``off`` is the eager step, bit for bit what every committed number was made with. ``on`` compiles the step with
torch.compile (inductor) once per bucket shape; where compilation fails, or no C++ compiler is found, one line says
so and the eager step runs. ``auto`` is what was measured faster on this kind of device: the eager step on a CPU
and on a GPU (docs/performance.md, 'The compiled step': the compiled step was slower or barely faster in training,
and its compile time is minutes). Every artifact's ``runtime`` records the mode asked for and the one in effect.
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

CHOICES = {"auto": "the eager step where compiling was not measured faster (today: everywhere)",
           "on": "the step compiled by torch.compile (inductor), eager where it cannot compile",
           "off": "the eager step (every committed number)"}
"""compile values -> what they do"""

_state: dict[str, object] = {"asked": "off", "on": False, "why": None, "seconds": 0.0, "shapes": 0}


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
    C++ compiler (a CPU device) one line says so and the eager step runs."""
    on = resolve(mode, device)
    _state.update(asked=mode, on=on, why=None)
    if on and not str(device).startswith("cuda") and compiler() is None:
        fall_back("no C++ compiler was found (set CXX, or install g++)")
        return False
    if on:
        os.environ.setdefault("TORCHINDUCTOR_CACHE_DIR", str(cache_dir()))
    return on


def enabled() -> bool:
    """Whether the step compiles now (compile=on and nothing has failed)."""
    return bool(_state["on"])


def fall_back(why: str) -> None:
    """Compilation cannot be used in this process: the eager step runs from here on, said in one line."""
    if _state["on"] or _state["why"] is None:
        print(f"neurosym: warning: compile={_state['asked']}: {why}; the eager step runs (compile=off)",
              file=sys.stderr)
    _state.update(on=False, why=why)


def compiled(seconds: float) -> None:
    """Count one bucket shape compiled, taking ``seconds`` (the first call, compilation included)."""
    _state["seconds"] = float(_state["seconds"]) + seconds  # type: ignore[arg-type]
    _state["shapes"] = int(_state["shapes"]) + 1  # type: ignore[call-overload]


def record() -> dict[str, object]:
    """The compile mode as recorded in every artifact's runtime: asked, in effect, why not, and the compile cost."""
    return {"asked": _state["asked"], "in_effect": "on" if _state["on"] else "off", "why_off": _state["why"],
            "compile_seconds": round(float(_state["seconds"]), 3), "shapes_compiled": _state["shapes"]}  # type: ignore[arg-type]
