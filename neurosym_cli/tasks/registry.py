"""Tasks by import path: a task YAML names its class (``_target_``, Hydra's convention), the class names its schema
(``Config``), and every process (the console script, joblib and submitit workers, process pools, a notebook)
resolves the same class the same way. Nothing is registered at run time, so nothing is lost in a worker.

Where task YAMLs are found (``task_yamls``): the package's conf/task/, the user's ``--config-dir`` and
``hydra.searchpath`` directories (their task/ folders), and installed packages' entry points in the group
``neurosym.tasks`` (``name = "package.module:Class"``). Stdlib and omegaconf only: the schema of the paper's tasks
is read without importing torch (their modules import it lazily).
"""

from __future__ import annotations

import dataclasses
import difflib
import importlib
import inspect
import os
import sys
from pathlib import Path
from typing import Any, Iterable

from ..config import TaskConfig
from ..errors import ConfigError, did_you_mean
from .base import DIMENSIONS, REQUIRED, target_reads_agent

ENTRY_POINTS = "neurosym.tasks"
"""entry-point group of installed task packages: name -> 'package.module:Class'"""


def import_target(target: str, *, key: str = "task._target_") -> Any:
    """The object at ``package.module.Class`` (or ``package.module:Class``); a one-line error when it does not
    import, with the import error's message. ``key``: where the path was given (task._target_, baseline._target_,
    an entry point), named in the errors."""
    if not isinstance(target, str) or not target.strip():
        raise ConfigError(f"{key} is missing: a task YAML names its class, e.g. "
                          "`_target_: mypackage.tasks.RingTask` (docs/extending.md)")
    module, sep, attr = target.partition(":")
    if not sep:
        module, _, attr = target.rpartition(".")
    if not module or not attr:
        raise ConfigError(f"{key}={target!r} is not an import path like package.module.Class")
    add_import_paths([p for p in os.environ.get(IMPORT_PATHS_ENV, "").split(os.pathsep) if p])  # in a worker
    try:
        mod = importlib.import_module(module)
    except (Exception, SystemExit) as e:  # ImportError, the user's module failing or calling sys.exit() at import
        msg = str(e).splitlines()[0] if str(e) else type(e).__name__
        if isinstance(e, SystemExit):  # would end the command with its code (0: "success", having done nothing)
            msg = f"it called sys.exit({e.code!r}) while being imported; a plugin module must only define classes"
        near = _near_module(module) if isinstance(e, ModuleNotFoundError) and e.name == module else ""
        raise ConfigError(f"{key}={target!r}: cannot import {module!r} ({type(e).__name__}: {msg})"
                          + (near or "; is it on the Python path (the working directory, or an installed "
                                     "package)?")) from None
    if not hasattr(mod, attr):
        classes = [n for n, v in vars(mod).items() if inspect.isclass(v) and not n.startswith("_")]
        near = _did_you_mean(attr, classes, f"{module}.")
        raise ConfigError(f"{key}={target!r}: module {module!r} has no {attr!r}"
                          f"{_shadowed(module, mod) or near}")
    return getattr(mod, attr)


def _near_module(module: str) -> str:
    """'; did you mean 'x'?' for a module name that does not exist: the closest module of its package, or of the
    user's import paths (their *.py files and packages) and the installed task modules for a top-level name."""
    import pkgutil

    parent, _, leaf = module.rpartition(".")
    if parent:
        try:
            where = list(getattr(importlib.import_module(parent), "__path__", []))
        except Exception:
            return ""
        return _did_you_mean(leaf, [m.name for m in pkgutil.iter_modules(where)], f"{parent}.")
    dirs = [d for d in os.environ.get(IMPORT_PATHS_ENV, "").split(os.pathsep) if d]
    return _did_you_mean(leaf, [m.name for m in pkgutil.iter_modules(dirs)] + ["neurosym", "neurosym_cli"], "")


def _did_you_mean(name: str, known: list[str], prefix: str) -> str:
    """'; did you mean '<prefix><nearest>'?' (the nearest of ``known`` to ``name``, difflib), or ''."""
    near = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
    return f"; did you mean {prefix + near[0]!r}?" if near else ""


def _shadowed(module: str, mod: Any) -> str:
    """'; ...' when a user's file of that name lies in an import path but Python's or a package's module of the
    same name came first (the user's directories come last on sys.path), else ''."""
    top = module.partition(".")[0]
    mine = [Path(d) / f"{top}.py" for d in os.environ.get(IMPORT_PATHS_ENV, "").split(os.pathsep) if d]
    mine = [f for f in mine if f.is_file()]
    where = getattr(mod, "__file__", None) or "built in"
    if mine and not any(Path(where).resolve() == f.resolve() for f in mine if where != "built in"):
        return (f"; {module!r} is {where}, not your {mine[0]}: the standard library and installed packages come "
                f"first, so rename your module (and _target_)")
    return ""


def task_class(target: str) -> type:
    """The task class of an import path, checked against the protocol (tasks/base.py ``Task``): its methods and a
    ``Config`` schema extending TaskConfig. A class that does not satisfy it is one line naming what is missing."""
    cls = import_target(target)
    if not inspect.isclass(cls):
        raise ConfigError(f"task._target_={target!r} is not a class")
    missing = [m for m in REQUIRED if not callable(getattr(cls, m, None))]
    if missing:
        raise ConfigError(f"task class {target} lacks {', '.join(f'{m}()' for m in missing)} of the task protocol "
                          f"(docs/extending.md)")
    target_reads_agent(cls)  # its form, read once here; a target taking no action is refused
    schema = getattr(cls, "Config", None)
    if not (inspect.isclass(schema) and dataclasses.is_dataclass(schema) and issubclass(schema, TaskConfig)):
        raise ConfigError(f"task class {target} needs `Config`, a dataclass schema extending "
                          f"neurosym_cli.config.TaskConfig (docs/extending.md)")
    return cls


def schema_of(target: str) -> type[TaskConfig]:
    return task_class(target).Config


def closest(key: str, known: Iterable[str]) -> str:
    """'; did you mean 'x'?' for the nearest known key, or ''."""
    return did_you_mean(key, known)


def typed_task(node: Any) -> Any:
    """A composed task node (a DictConfig from the task's YAML and overrides) merged into its class's schema: a
    structured node with every field and default, type-checked. Unknown keys and wrong types are one line."""
    from omegaconf import OmegaConf
    from omegaconf.errors import OmegaConfBaseException

    target = node.get("_target_") if hasattr(node, "get") else None
    schema = schema_of(target)  # type: ignore[arg-type]
    fields = {f.name for f in dataclasses.fields(schema)}
    for key in node.keys():
        if key not in fields:
            raise ConfigError(f"unknown key 'task.{key}' for task {node.get('name', '?')} ({schema.__name__})"
                              f"{closest(str(key), fields)}")
    try:
        typed = OmegaConf.merge(OmegaConf.structured(schema), node)
    except OmegaConfBaseException as e:
        raise ConfigError(value_problem(e, "task.", f"task {node.get('name', '?')}'s YAML")) from None
    return typed


def value_problem(e: Exception, prefix: str, where: str) -> str:
    """An OmegaConf type error as the command line's: "task.radius takes a float, not 'abc' (in task ring's
    YAML)", naming the key its first line leaves out (``prefix``: the key's section, ``where``: its file)."""
    first = str(e).splitlines()[0] if str(e) else type(e).__name__
    key = getattr(e, "full_key", None)
    if not key:
        return f"{prefix.rstrip('.')}: {first}"
    import re

    m = re.match(r"Value '(.*)' of type '\w+' could not be converted to (\w+)", first)
    what = f"takes {'an' if m.group(2)[0] in 'AEIOU' else 'a'} {m.group(2).lower()}, not {m.group(1)!r}" if m else first
    return f"{prefix}{key} {what} (in {where})" if m else f"{prefix}{key}: {what} (in {where})"


def make_task(cfg: TaskConfig, horizon: int | None = None) -> Any:
    """The task of a typed task config; ``horizon`` overrides its T. Its dimensions are checked once here."""
    cls = task_class(cfg._target_)
    task = cls(cfg, horizon)
    bad = [d for d in DIMENSIONS if not isinstance(getattr(task, d, None), int) or getattr(task, d) < 1]
    if bad:
        raise ConfigError(f"task {cfg.name} ({cfg._target_}) must set positive integers {', '.join(bad)}")
    return task


def probe(task: Any, name: str, *, max_agents: int | None = None) -> None:
    """Reset two episodes, observe them and step them once with a zero action: wrong shapes, and a cost that is not
    finite, are one line naming the method, before any training starts. ``max_agents``: the config's N of the
    largest episode (``TaskConfig.max_agents``), which the memory and K < N checks trust; an episode with more
    agents is one line saying what to add."""
    import torch

    from .base import Rng, TaskState

    gen = torch.Generator().manual_seed(0)
    try:
        buckets = task.reset(2, gen)
    except Exception as e:
        raise ConfigError(f"task {name}: reset(2, gen) failed ({type(e).__name__}: {str(e).splitlines()[0]})") \
            from None
    if not isinstance(buckets, list) or not buckets or not all(isinstance(b, TaskState) for b in buckets):
        raise ConfigError(f"task {name}: reset() must return a non-empty list of TaskState buckets, got "
                          f"{type(buckets).__name__}")
    s = buckets[0]
    if s.pos.dim() != 3 or s.pos.shape[-1] != 2:
        raise ConfigError(f"task {name}: state.pos must be (B, N, 2), got {tuple(s.pos.shape)}")
    most = max(b.n_agents for b in buckets)
    if max_agents is not None and most > max_agents:
        raise ConfigError(f"task {name}: reset() made an episode of {most} agents, but its config's max_agents is "
                          f"{max_agents} (agents_per_group by default); give its schema a max_agents property "
                          "returning the largest N (docs/extending.md, section 2)")
    obs = task.observe(s, Rng(gen))
    b, n = s.batch, s.n_agents
    want = {"agent": (b, n, task.obs_dim), "rel": (b, n, n, task.pair_dim)}
    for field, shape in want.items():
        got = tuple(obs.agent.shape if field == "agent" else obs.rel_shape)  # a pair source is not built here
        if got != shape:
            raise ConfigError(f"task {name}: observe() gives {field} of shape {got}, but obs_dim/pair_dim declare "
                              f"{shape}")
    action = torch.zeros(b, n, task.action_dim)
    try:
        cost = task.cost(task.step(s, action), action)
    except Exception as e:
        raise ConfigError(f"task {name}: step() and cost() of a zero action failed ({type(e).__name__}: "
                          f"{str(e).splitlines()[0] if str(e) else ''})") from None
    if not isinstance(cost, torch.Tensor) or not bool(torch.isfinite(cost).all()):
        what = (f"a {type(cost).__name__}" if not isinstance(cost, torch.Tensor)
                else f"{float(cost[~torch.isfinite(cost)].flatten()[0])}")
        raise ConfigError(f"task {name}: cost() of a zero action from reset()'s first state is {what}, not a finite "
                          "tensor: the task's cost is non-finite before any training (not the learning rate); fix "
                          "its cost() or step() (a norm or division at distance 0? neurosym.tasks.safe_norm)")


# ------------------------------------------------------------------------------ where task YAMLs are found
def _installed_conf() -> Path | None:
    from importlib.util import find_spec

    spec = find_spec("neurosym_cli.conf")
    return Path(spec.origin).parent if spec and spec.origin else None


def search_dirs(args: list[str]) -> list[Path]:
    """Config directories a command line adds: ``--config-dir DIR`` / ``-cd DIR`` / ``--config-dir=DIR`` and
    ``hydra.searchpath=[file://DIR, pkg://package.conf, ...]``."""
    out: list[Path] = []
    for i, a in enumerate(args):
        if a in ("--config-dir", "-cd") and i + 1 < len(args):
            out.append(Path(args[i + 1]))
        elif a.startswith(("--config-dir=", "-cd=")):
            out.append(Path(a.split("=", 1)[1]))
        elif a.lstrip("+").startswith("hydra.searchpath="):
            for item in a.split("=", 1)[1].strip("[]").split(","):
                item = item.strip().strip("'\"")
                if item.startswith("file://"):
                    out.append(Path(item[len("file://"):]))
                elif item.startswith("pkg://"):
                    from importlib.util import find_spec

                    try:
                        spec = find_spec(item[len("pkg://"):])
                    except (ImportError, ValueError):
                        spec = None
                    if spec and spec.submodule_search_locations:
                        out.append(Path(list(spec.submodule_search_locations)[0]))
                elif item:
                    out.append(Path(item))
    return [p.expanduser().absolute() for p in out]


def entry_point_tasks() -> dict[str, str]:
    """Installed packages' tasks: entry-point name -> import path of the class."""
    from importlib.metadata import entry_points

    try:
        return {ep.name: ep.value for ep in entry_points(group=ENTRY_POINTS)}
    except Exception:  # a broken distribution's metadata must not break the CLI
        return {}


def task_yamls(args: list[str] | None = None) -> dict[str, Path]:
    """Task name -> its file, the user's directories last (Hydra's search path: later wins). The name is the path
    below task/ without the suffix, as Hydra names a nested option: task/vmas/navigation.yaml is ``vmas/navigation``."""
    out: dict[str, Path] = {}
    dirs = [d for d in [_installed_conf()] if d is not None] + search_dirs(args or [])
    for d in dirs:
        root = d / "task"
        for f in sorted(root.rglob("*.yaml")):
            out[f.relative_to(root).with_suffix("").as_posix()] = f
    return out


def task_choices(args: list[str] | None = None) -> list[str]:
    """Every task a command line can name: YAMLs of the search path and installed entry points."""
    return sorted(set(task_yamls(args)) | set(entry_point_tasks()))


def yaml_target(name: str, args: list[str] | None = None, _seen: tuple = ()) -> str | None:
    """The ``_target_`` a task YAML resolves to (following its defaults list within the task group), or the entry
    point's; None when it names none."""
    files = task_yamls(args)
    if name not in files:
        return entry_point_tasks().get(name)
    from omegaconf import OmegaConf

    try:
        node = OmegaConf.to_container(OmegaConf.load(files[name]))
    except Exception:
        return None
    if not isinstance(node, dict):
        return None
    if node.get("_target_"):
        return str(node["_target_"])
    for d in node.get("defaults") or []:
        if not isinstance(d, str) or d == "_self_" or d.startswith("/"):
            continue
        # a defaults entry is relative to the YAML's own folder (Hydra): `base` in task/vmas/ is vmas/base
        ref = f"{name.rpartition('/')[0]}/{d}".lstrip("/")
        if ref not in _seen:
            t = yaml_target(ref, args, _seen + (name,))
            if t:
                return t
    return None


def import_paths(args: list[str]) -> list[str]:
    """Directories a user's task module is imported from: the working directory and the parent of each config
    directory the command line adds (``examples/ring/conf`` -> ``examples/ring``)."""
    out = [os.getcwd()]
    for d in search_dirs(args):
        out += [str(d), str(d.parent)]
    return list(dict.fromkeys(out))


IMPORT_PATHS_ENV = "NEUROSYM_IMPORT_PATHS"
"""the directories of users' task modules, for every process that resolves a task (workers inherit it)"""


def add_import_paths(paths: list[str]) -> None:
    """Put ``paths`` at the END of this process's sys.path and in NEUROSYM_IMPORT_PATHS, which ``import_target``
    reads in every worker (joblib, process pools, submitit). At the end, not the front and not on PYTHONPATH
    (which Python puts before the standard library): a user's own datetime.py or queue.py in the working directory
    never replaces the module of that name; their task module is found there all the same."""
    for p in paths:
        if p not in sys.path:
            sys.path.append(p)
    old = [p for p in os.environ.get(IMPORT_PATHS_ENV, "").split(os.pathsep) if p]
    os.environ[IMPORT_PATHS_ENV] = os.pathsep.join(dict.fromkeys(old + paths))


# ------------------------------------------------------------------ the command line's tasks and their keys
def task_names(args: list[str], config_name: str) -> list[str]:
    """The tasks a command line runs: its ``task=`` values (a sweep lists several), else the default of the
    command's primary config (conf/<config_name>.yaml)."""
    for a in args:
        key, sep, value = a.partition("=")
        if sep and key.lstrip("+") == "task":
            return [v for v in value.split(",") if v]
    return [_default_task(config_name)]


def _default_task(config_name: str) -> str:
    """The ``task:`` entry of a primary config's defaults list (random-cross for every verb today)."""
    from importlib.util import find_spec

    from omegaconf import OmegaConf

    spec = find_spec("neurosym_cli.conf")
    if spec is None or spec.origin is None:
        return "random-cross"
    from pathlib import Path

    node = OmegaConf.to_container(OmegaConf.load(Path(spec.origin).parent / f"{config_name}.yaml"))
    for d in node.get("defaults", []) if isinstance(node, dict) else []:
        if isinstance(d, dict) and "task" in d:
            return str(d["task"])
    return "random-cross"


def check_not_builtin(name: str, args: list[str]) -> None:
    """Refuse a user's task YAML with the name of a built-in task: Hydra loads the built-in one (the package's
    config directory comes first), so the user's file would be silently ignored."""
    conf = _installed_conf()
    if conf is None or not (conf / "task" / f"{name}.yaml").is_file():
        return
    mine = [d / "task" / f"{name}.yaml" for d in search_dirs(args) if d.resolve() != conf.resolve()]
    mine = [f for f in mine if f.is_file()]
    if mine:
        folder, _, stem = name.rpartition("/")
        other = f"{folder}/my-{stem}".lstrip("/")
        raise ConfigError(f"task={name}: your {mine[0]} has the name of a built-in task, and the built-in one is what "
                          f"runs (yours would be ignored); rename yours, e.g. task/{other}.yaml, and run task={other}")


def task_schemas(args: list[str], config_name: str) -> list[type]:
    """The schemas of the tasks a command line runs (resolved through their YAMLs' ``_target_``): a class that
    does not import or breaks the protocol, or a user's YAML named like a built-in task, is a ConfigError (one
    line) here, before Hydra runs. A task without a YAML is left to the choices check."""
    out = []
    for name in task_names(args, config_name):
        check_not_builtin(name, args)
        target = yaml_target(name, args)
        if target is not None:
            out.append(schema_of(target))
    return out


def force_task_keys(args: list[str], schemas: list[type]) -> list[str]:
    """``task.K=V`` as ``++task.K=V`` for every field K of the task's schema: a task YAML names only what it changes,
    so Hydra (which composes the task node untyped) would refuse a schema field the YAML leaves out."""
    fields = {f.name for s in schemas for f in dataclasses.fields(s)}
    out = []
    for a in args:
        key, sep, value = a.partition("=")
        if sep and key.startswith("task.") and key[len("task."):] in fields:
            a = f"++{key}={value}"
        out.append(a)
    return out
