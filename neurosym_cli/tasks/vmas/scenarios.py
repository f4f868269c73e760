"""Importing VMAS (an optional extra: the one-line error names it) and finding a scenario by name or module:Class."""

from __future__ import annotations

import importlib
from typing import Any

from ...errors import ConfigError

EXTRA = "pip install -e '.[vmas]' in the neurosym checkout (or pip install 'vmas>=1.5'; GPLv3)"


def require_vmas() -> Any:
    """The vmas package, or the one-line error naming the extra."""
    try:
        import vmas
    except ImportError:
        raise ConfigError(f"VMAS tasks need the vmas extra: {EXTRA}") from None
    return vmas


def builtin_scenarios() -> list[str]:
    """Names of the scenarios shipped with VMAS (its own lists: scenarios, mpe_scenarios, debug_scenarios)."""
    vmas = require_vmas()
    return sorted({*vmas.scenarios, *getattr(vmas, "mpe_scenarios", ()), *getattr(vmas, "debug_scenarios", ())})


def scenario_of(spec: str) -> Any:
    """A fresh BaseScenario for ``spec``: a VMAS scenario name (``navigation``) or ``module:Class`` (a user's
    BaseScenario subclass). Unknown names are one line with the available ones."""
    require_vmas()
    from vmas.simulator.scenario import BaseScenario

    if ":" in spec:
        from ..registry import import_target

        cls = import_target(spec)
        if not (isinstance(cls, type) and issubclass(cls, BaseScenario)):
            raise ConfigError(f"task.scenario={spec!r} is not a vmas BaseScenario subclass")
        return cls()
    names = builtin_scenarios()
    if spec not in names:
        raise ConfigError(f"unknown VMAS scenario {spec!r}; choose one of: {', '.join(names)} "
                          f"(or task.scenario=module:Class for your own BaseScenario)")
    return importlib.import_module("vmas.scenarios").load(f"{spec}.py").Scenario()


def make_env(spec: str, n: int, b: int, device: Any, size_kwarg: str, kwargs: dict[str, Any]) -> Any:
    """A differentiable VMAS environment of scenario ``spec`` with ``n`` agents (keyword ``size_kwarg``) and ``b``
    parallel episodes; the scenario's own refusals (a bad keyword, an impossible size) become one line."""
    import warnings

    vmas = require_vmas()
    kw = {**kwargs, size_kwarg: n}
    scenario = scenario_of(spec)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            env = vmas.make_env(scenario, num_envs=b, device=device, continuous_actions=True,
                                grad_enabled=True, seed=0, **kw)
    except ConfigError:
        raise
    except Exception as e:  # noqa: BLE001 (whatever the scenario raises is reported, never a traceback)
        raise ConfigError(f"task.scenario={spec!r} with {kw}: VMAS refused "
                          f"({type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''})") from None
    for w in caught:
        if "not used by the scenario" in str(w.message):  # VMAS only warns, and trains without them
            raise ConfigError(unused_kwargs(spec, scenario, kwargs))
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)  # anything else, as VMAS said it
    return env


def scenario_keywords(scenario: Any) -> list[str]:
    """The make_world keywords a scenario reads (``kwargs.pop("x", ...)`` / ``kwargs.get("x", ...)`` in its
    source: VMAS scenarios take ``**kwargs``, so the signature names none); [] when its source is not readable."""
    import inspect
    import re

    try:
        src = inspect.getsource(type(scenario).make_world)
    except (OSError, TypeError):
        return []
    return sorted(set(re.findall(r"kwargs\.(?:pop|get)\(\s*[\"'](\w+)[\"']", src)))


def unused_kwargs(spec: str, scenario: Any, kwargs: dict[str, Any]) -> str:
    """One line naming the task.scenario_kwargs a scenario does not read, with the nearest it does."""
    import difflib

    known = scenario_keywords(scenario)
    bad = [k for k in kwargs if k not in known] if known else sorted(kwargs)
    near = {k: difflib.get_close_matches(k, known, n=1, cutoff=0.6) for k in bad}
    hints = "; ".join(f"did you mean {near[k][0]!r} for {k!r}?" for k in bad if near[k])
    return (f"task.scenario_kwargs: VMAS scenario {spec!r} does not use {', '.join(map(repr, bad))} (it would train "
            f"without {'it' if len(bad) == 1 else 'them'})" + (f"; {hints}" if hints else "")
            + (f"; it reads: {', '.join(known)}" if known else ""))
