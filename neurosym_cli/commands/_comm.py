"""The communication provider of a baseline, with its synthesized artifact (program or tree) loaded."""

from __future__ import annotations

from .. import paths
from ..config import ConfigError, RunConfig
from ..policy import make_comm
from ..policy.comm import CommProvider, ProgramComm, TreeComm
from ..utils.io import ArtifactError, load_program, read_json


def baseline_comm(cfg: RunConfig) -> CommProvider:
    if cfg.baseline.comm == "program":
        program = load_program(paths.program_file(cfg), paths.synth_command(cfg))
        if program.n_rounds != cfg.task.rounds:
            raise ConfigError(f"the program has {program.n_rounds} round(s), the task {cfg.task.rounds}")
        return ProgramComm(program, cfg.task.kind, cfg.features)
    if cfg.baseline.comm == "tree":
        from ..synth.tree import TreeModel

        path = paths.tree_file(cfg)
        if not path.exists():
            raise ArtifactError(f"no tree at {path}; create it with `{paths.synth_command(cfg)}`")
        rounds = [TreeModel.from_dict(t) for t in read_json(path)["rounds"]]
        if len(rounds) != cfg.task.rounds:
            raise ConfigError(f"the tree file has {len(rounds)} round(s), the task {cfg.task.rounds}")
        return TreeComm(rounds, cfg.task.kind, cfg.features)
    return make_comm(cfg.baseline.comm, cfg.rules)
