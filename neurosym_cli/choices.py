"""The choices of a config group (task=, baseline=, budget=) and of the Hydra launcher, checked in a list of
``key=value`` overrides: each check is a one-line error naming the choices, or None. Shared by the console script
(cli.py) and the Python API (api.py); cheap (no Hydra import)."""

from __future__ import annotations

import difflib


def conf_dir():
    """The package's conf/ folder (None when it cannot be found)."""
    from importlib.util import find_spec
    from pathlib import Path

    spec = find_spec("neurosym_cli.conf")
    return Path(spec.origin).parent if spec and spec.origin else None


def choices(group: str, args: list[str] | None = None) -> list[str]:
    """The options of a config group: the registered baselines; the tasks of the search path (the package's, the
    command line's config directories, installed entry points); or the YAML files of conf/<group>/."""
    if group == "baseline":
        from neurosym_cli.schemes import SCHEMES

        return list(SCHEMES)
    if group == "task":
        from neurosym_cli.tasks.registry import task_choices

        return task_choices(args)
    conf = conf_dir()
    return sorted(p.stem for p in (conf / group).glob("*.yaml")) if conf is not None else []


def check_choices(args: list[str], sources: dict[str, str] | None = None) -> str | None:
    """A one-line error for an unknown option of a config group (task=, baseline=, budget=), else None; ``sources``:
    where a defaulted group's value came from (defaults.py), named in its error.

    Hydra would say the same over a dozen lines; this names the valid choices and stays cheap (no Hydra import).
    """
    for a in args:
        key, sep, value = a.partition("=")
        if not sep or key.startswith(("+", "~", "hydra")) or key not in ("task", "baseline", "budget"):
            continue
        known = choices(key, args)
        if not known:
            return None
        for v in value.split(","):  # sweeps: task=a,b
            if v not in known and not v.startswith(("glob(", "choice(", "range(")):
                if key == "baseline":  # the nearest scheme and every one, or why an installed plugin cannot be used
                    from neurosym_cli.schemes.registry import unknown

                    return unknown(v)
                where = f" (the default set by {sources[key]})" if key in (sources or {}) else ""
                near = difflib.get_close_matches(v, known, n=1, cutoff=0.6)
                hint = f"; did you mean {key}={near[0]}? (choices: {', '.join(known)})" if near else \
                    f"; choose one of: {', '.join(known)}"
                return f"unknown {key} {v!r}{where}{hint}"
    return None


_SUBMITIT = ("hydra_plugins.hydra_submitit_launcher", "the cluster extra: pip install -e '.[cluster]' in the "
             "neurosym checkout (or pip install hydra-submitit-launcher)")
LAUNCHER_PLUGINS = {
    "joblib": ("hydra_plugins.hydra_joblib_launcher", "hydra-joblib-launcher (a dependency of neurosym; reinstall it)"),
    **{name: _SUBMITIT for name in ("submitit_local", "submitit_slurm", "slurm", "slurm_local")},
}
"""hydra/launcher choices -> (the plugin module they need, how to install it)"""


def launchers() -> list[str]:
    """The hydra/launcher choices: Hydra's basic one, this package's (conf/hydra/launcher/) and the plugins'."""
    from importlib.resources import files

    folder = files("neurosym_cli.conf") / "hydra" / "launcher"
    own = [p.name.removesuffix(".yaml") for p in folder.iterdir() if p.name.endswith(".yaml")]
    return sorted({"basic", *own, *LAUNCHER_PLUGINS})


_MODES = {"-m": "--multirun", "--multirun": "--multirun", "--cfg": "--cfg", "-c": "--cfg", "--info": "--info",
          "-i": "--info", "--run": "--run", "-r": "--run"}


def check_launcher(args: list[str]) -> str | None:
    """A one-line error for a launcher whose plugin is not installed (Hydra only says "Could not find"), or for
    two of Hydra's exclusive modes at once (-m with --cfg), else None."""
    from importlib.util import find_spec

    modes = sorted({_MODES[a] for a in args if a in _MODES})
    if len(modes) > 1:
        return f"{' and '.join(modes)} cannot be combined; use one (print the config of a sweep job without -m)"
    for a in args:
        key, sep, value = a.partition("=")
        if sep and key.lstrip("+") == "hydra/launcher" and value not in launchers():
            near = difflib.get_close_matches(value, launchers(), n=1, cutoff=0.6)
            return (f"unknown hydra/launcher {value!r}" + (f"; did you mean hydra/launcher={near[0]}?" if near else "")
                    + f" (choices: {', '.join(launchers())})")
        if sep and key.lstrip("+") == "hydra/launcher" and value in LAUNCHER_PLUGINS:
            module, how = LAUNCHER_PLUGINS[value]
            try:
                found = find_spec(module) is not None
            except (ImportError, ValueError):
                found = False
            if not found:
                return f"hydra/launcher={value} needs {how}"
    return None
