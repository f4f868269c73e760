"""A module imported on first use: the paper's task modules name torch at import time but import it only when a
tensor is made, so a command that only reads a task's schema and feature names (`neurosym show-program`, the
override checker, `--help`) stays free of torch's import cost."""

from __future__ import annotations

import importlib
from types import ModuleType


class LazyModule(ModuleType):
    """``torch = LazyModule("torch")``: the real module is imported at the first attribute access, and every
    attribute is cached on this object afterwards (no per-call indirection beyond a dict lookup)."""

    def __init__(self, name: str):
        super().__init__(name)
        self.__dict__["_lazy_target"] = name

    def __getattr__(self, attr: str):
        module = importlib.import_module(self.__dict__["_lazy_target"])
        value = getattr(module, attr)
        self.__dict__[attr] = value
        return value
