"""One Hydra app per subcommand, each with its own primary config (conf/<command>.yaml).

Imports only hydra and omegaconf; each command's module (and torch) is imported inside the task function,
so `--help`, `--cfg` and completion stay fast.
"""

from __future__ import annotations

import importlib
import os
import sys

import hydra
from hydra.core.config_store import ConfigStore
from omegaconf import DictConfig, OmegaConf

from ..config import RunConfig
from ..errors import EXIT_CONFIG, EXIT_FAILED, cut_words, name_problem, resource_problem
from ..schemes import SCHEMES, default_baselines
from ..run.layout import fail_suffix  # link-failure runs are apart from the task's own: <task>-fail<p>
from ..tasks.registry import entry_point_tasks
from . import COMMANDS

if not OmegaConf.has_resolver("fail_suffix"):
    OmegaConf.register_new_resolver("fail_suffix", fail_suffix)


def path_name(name: str) -> str:
    """A name as one directory of exp_dir; one that is not (``errors.name_problem``) becomes a placeholder, so
    Hydra's log directory, made from exp_dir before the schema refuses the name in one line, stays in the runs
    root."""
    return "invalid-name" if name_problem(str(name)) else str(name)


if not OmegaConf.has_resolver("path_name"):
    OmegaConf.register_new_resolver("path_name", path_name)

_store = ConfigStore.instance()
_schema = OmegaConf.structured(RunConfig)
_schema.baselines = default_baselines()  # the pipeline's default, from the registry (config.py cannot see it)
_store.store(name="run_schema", node=_schema)
for _name, _target in entry_point_tasks().items():  # installed packages' tasks: task=<name> (tasks/registry.py)
    _store.store(group="task", name=_name, node={"_target_": _target, "name": _name})
_stored: dict[str, object] = {}


def store_schemes() -> None:
    """The config group baseline=..., one option per registered scheme, its class the schema (again for a scheme
    registered since, by ``baseline._target_`` in compose_config)."""
    for b in SCHEMES.values():
        if _stored.get(b.name) is not b:
            _store.store(group="baseline", name=b.name, node=b)
            _stored[b.name] = b


store_schemes()


def _make(name: str):
    @hydra.main(version_base="1.3", config_path="pkg://neurosym_cli.conf", config_name=name)
    def app(cfg: DictConfig) -> object:
        from ._run import run_command

        if cfg.get("cmd") != name:  # `neurosym train -cn eval` would otherwise run train on eval's config
            raise SystemExit(f"neurosym: error: config {cfg.get('cmd')!r} is not a {name!r} config")
        module = importlib.import_module(f"neurosym_cli.commands.{name}")
        return run_command(name, cfg, module.run)

    return _one_line(name, app)


def hydra_problem(e: Exception) -> str | None:
    """The one line of a failure before (or around) a command's own wrapper: Hydra's composition, its log
    directory (a full or read-only disk), an interpolation that does not resolve; None for a bug."""
    from hydra.errors import HydraException
    from omegaconf.errors import OmegaConfBaseException

    if isinstance(e, (HydraException, OmegaConfBaseException)):
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        return f"{first}; an interpolation reads a key of the config (${{seed}}) or a set variable " \
               "(${oc.env:VAR,default})" if "nterpolation" in type(e).__name__ + first else first
    return resource_problem(e)


def _one_line(name: str, app):
    """The app with Hydra's own failures as one line and exit 2 (a disk or memory problem: 1), as run_command does
    for the command's: Hydra raises them (HYDRA_FULL_ERROR) instead of printing a cut traceback; a user who set
    HYDRA_FULL_ERROR gets them whole, as Hydra documents."""
    def run() -> object:
        if os.environ.get("HYDRA_FULL_ERROR"):
            return app()
        os.environ["HYDRA_FULL_ERROR"] = "1"
        try:
            return app()
        except Exception as e:
            msg = hydra_problem(e)
            if msg is None:
                raise
            print(f"neurosym {name.replace('_', '-')}: error: {cut_words(msg)}", file=sys.stderr)
            raise SystemExit(EXIT_FAILED if resource_problem(e) else EXIT_CONFIG) from None  # Hydra's: the config's
        finally:
            os.environ.pop("HYDRA_FULL_ERROR", None)

    return run


APPS = {module: _make(module) for module, _ in COMMANDS.values()}


def compose_config(cmd: str, overrides: list[str] | None = None, config_dir: str | None = None) -> RunConfig:
    """The typed config ``neurosym <cmd> <overrides>`` runs with, outside any command (the Python API, benchmarks,
    notebooks): the same override checks as the console script, the task's schema keys, ``config_dir`` as
    ``--config-dir``. Bad input raises UserError with the CLI's one-line message."""
    from pathlib import Path

    from hydra import compose, initialize_config_module

    from ..errors import UserError
    from ..overrides import check
    from ..schemes.registry import targets_in
    from ..tasks.registry import add_import_paths, force_task_keys, import_paths, task_schemas
    from ._run import typed_config

    extra = ["--config-dir", str(config_dir)] if config_dir else []
    add_import_paths(import_paths(extra))
    items, bad = targets_in(list(overrides or []))  # baseline._target_=pkg.Class: registered, then baseline=<name>
    if bad:
        raise UserError(bad)
    store_schemes()
    schemas = task_schemas(items + extra, cmd)
    bad = check(items, schemas)
    if bad:
        raise UserError(bad)
    items = force_task_keys(items, schemas)
    if config_dir:
        items.append(f"hydra.searchpath=[file://{Path(config_dir).absolute()}]")
    try:
        with initialize_config_module("neurosym_cli.conf", version_base="1.3"):
            cfg = compose(cmd, overrides=items)
    except Exception as e:  # Hydra's missing option, grammar errors: the console script's one line
        msg = hydra_problem(e) or (str(e).splitlines()[0] if str(e) else type(e).__name__)
        raise UserError(cut_words(msg)) from None
    return typed_config(cfg)
