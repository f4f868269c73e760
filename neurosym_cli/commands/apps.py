"""One Hydra app per subcommand, each with its own primary config (conf/<command>.yaml).

Imports only hydra and omegaconf; each command's module (and torch) is imported inside the task function,
so `--help`, `--cfg` and completion stay fast.
"""

from __future__ import annotations

import importlib

import hydra
from hydra.core.config_store import ConfigStore
from omegaconf import DictConfig, OmegaConf

from ..config import TASK_SCHEMAS, RunConfig
from ..schemes import SCHEMES, default_baselines
from . import COMMANDS

def fail_suffix(p: float) -> str:
    """Run directories of link-failure runs are apart from the task's own: <task>-fail<p> (nothing at 0)."""
    return f"-fail{float(p):g}" if float(p) > 0 else ""


if not OmegaConf.has_resolver("fail_suffix"):
    OmegaConf.register_new_resolver("fail_suffix", fail_suffix)

_store = ConfigStore.instance()
_schema = OmegaConf.structured(RunConfig)
_schema.baselines = default_baselines()  # the pipeline's default, from the registry (config.py cannot see it)
_store.store(name="run_schema", node=_schema)
for _family, _schema in TASK_SCHEMAS.items():  # what a conf/task/*.yaml extends
    _store.store(name=f"{_family}_task_schema", node=_schema)  # no group: not a choice of its own in --help
for _b in SCHEMES.values():  # the config group baseline=..., one option per scheme, its class the schema
    _store.store(group="baseline", name=_b.name, node=_b)


def _make(name: str):
    @hydra.main(version_base="1.3", config_path="pkg://neurosym_cli.conf", config_name=name)
    def app(cfg: DictConfig) -> object:
        from ._run import run_command

        if cfg.get("cmd") != name:  # `neurosym train -cn eval` would otherwise run train on eval's config
            raise SystemExit(f"neurosym: error: config {cfg.get('cmd')!r} is not a {name!r} config")
        module = importlib.import_module(f"neurosym_cli.commands.{name}")
        return run_command(name, cfg, module.run)

    return app


APPS = {module: _make(module) for module, _ in COMMANDS.values()}


def compose_config(cmd: str, overrides: list[str] | None = None) -> RunConfig:
    """The typed config a command composes from conf/ and overrides, outside any command (benchmarks, notebooks)."""
    from hydra import compose, initialize_config_module
    from omegaconf import OmegaConf

    with initialize_config_module("neurosym_cli.conf", version_base="1.3"):
        return OmegaConf.to_object(compose(cmd, overrides=overrides or []))  # type: ignore[return-value]
