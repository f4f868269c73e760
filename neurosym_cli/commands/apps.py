"""One Hydra app per subcommand, each with its own primary config (conf/<command>.yaml).

Imports only hydra and omegaconf; each command's module (and torch) is imported inside the task function,
so `--help`, `--cfg` and completion stay fast.
"""

from __future__ import annotations

import importlib

import hydra
from hydra.core.config_store import ConfigStore
from omegaconf import DictConfig

from ..config import RunConfig

ConfigStore.instance().store(name="run_schema", node=RunConfig)


def _make(name: str):
    @hydra.main(version_base="1.3", config_path="pkg://neurosym_cli.conf", config_name=name)
    def app(cfg: DictConfig) -> object:
        from ._run import run_command

        if cfg.get("cmd") != name:  # `neurosym train -cn eval` would otherwise run train on eval's config
            raise SystemExit(f"neurosym: error: config {cfg.get('cmd')!r} is not a {name!r} config")
        module = importlib.import_module(f"neurosym_cli.commands.{name}")
        return run_command(name, cfg, module.run)

    return app


APPS = {n: _make(n) for n in ("train", "eval", "synth", "retrain", "show_program", "pipeline", "report")}
