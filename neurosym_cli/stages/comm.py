"""The communication provider of a baseline, with its synthesized artifact (program or tree) loaded and checked
against the task."""

from __future__ import annotations

from .. import artifacts, paths
from ..config import ConfigError, RunConfig, UserError
from ..policy.comm import CommProvider, ProgramComm, TreeComm, comm_module, make_comm, with_link_failure
from ..dsl.files import load_program
from .programs import check_program, feature_map  # noqa: F401  (re-exported)
from ..utils.io import ArtifactError, read_json


def baseline_comm(cfg: RunConfig, task=None) -> CommProvider:
    """The provider of ``cfg.baseline`` (a program or tree from the run directory or ``program=``, or a rule), with
    the task's link failure. ``task``: the task it runs on (built from the config when not given)."""
    return with_link_failure(_provider(cfg, task), cfg.task.link_failure)


def _provider(cfg: RunConfig, task=None) -> CommProvider:
    if cfg.baseline.comm == "program":
        path = paths.program_file(cfg)
        program = load_program(path, None if cfg.program else paths.synth_command(cfg))
        fmap = feature_map(cfg, task)
        check_program(program, cfg, str(path), fmap)
        return ProgramComm(program, fmap)
    if cfg.baseline.comm == "tree":
        from ..synth.tree import TreeModel

        path = paths.tree_file(cfg)
        if not path.exists():
            raise ArtifactError(f"no tree at {path}; create it with `{paths.synth_command(cfg)}`")
        try:
            rounds = [TreeModel.from_dict(t) for t in read_json(path)["rounds"]]
        except (UserError, KeyError, TypeError, ValueError, IndexError) as e:
            raise ArtifactError(f"corrupt tree {path} ({e}); `{paths.synth_command(cfg)} "
                                f"overwrite=true` fits it again") from None
        if len(rounds) != cfg.task.rounds:
            raise ConfigError(f"the tree file has {len(rounds)} round(s), the task {cfg.task.rounds}")
        return TreeComm(rounds, feature_map(cfg, task))
    if cfg.baseline.comm == "gated":
        from ..policy.gated import GatedComm

        from ..tasks import make_task

        return GatedComm(cfg.task.rounds, pair_dim=(task or make_task(cfg.task, cfg.horizon)).pair_dim)
    return make_comm(cfg.baseline.comm, cfg.rules)


def load_gate(comm: CommProvider, payload: dict, path, made_by: str) -> None:
    """Load an rl checkpoint's gate (``comm_state``) into ``comm``'s gate module; a fixed rule has none."""
    gate = comm_module(comm)
    if gate is None:
        return
    try:
        gate.load_state_dict(payload["comm_state"])
    except (KeyError, RuntimeError, TypeError) as e:
        raise ArtifactError(f"{path} has no usable communication gate ({str(e).splitlines()[0]}); "
                            f"`{made_by} overwrite=true` trains it again") from None


def comm_identity(cfg: RunConfig, comm: CommProvider) -> str:
    """SHA-1 of what a retrained model is retrained under: the program's rules (comments aside) or the tree file."""
    import hashlib

    from ..dsl.printer import to_text

    if cfg.baseline.comm == "tree":
        data = paths.tree_file(cfg).read_bytes()
    else:
        data = to_text(comm.program).encode()  # type: ignore[attr-defined]
    return hashlib.sha1(data).hexdigest()


def load_baseline(cfg: RunConfig, device, task=None):
    """(policy on ``device``, task, provider) of ``cfg.baseline``: its trained weights and its communication, on
    ``task`` (built from the config when not given). A partly trained model is used with a warning naming the
    command that finishes it."""
    from ..tasks import make_task
    from ..utils.console import log

    payload = artifacts.load_checkpoint(paths.train_dir(cfg) / "model.pt", paths.train_command(cfg))
    if not payload.get("done"):
        log.warning("the model is only partly trained (step %d); using it anyway; `%s` finishes it",
                    payload["fit"]["step"], paths.train_command(cfg))
    policy = artifacts.policy_from_payload(payload).to(device)
    task = task or make_task(cfg.task, cfg.horizon)
    comm = baseline_comm(cfg, task)
    load_gate(comm, payload, paths.train_dir(cfg) / "model.pt", paths.train_command(cfg))
    if (gate := comm_module(comm)) is not None:
        gate.to(device)
    if payload.get("made_under") and payload["made_under"] != comm_identity(cfg, comm):
        log.warning("the retrained model was made under another program (or tree) than the one there now; "
                    "`%s overwrite=true` retrains it under this one", paths.retrain_command(cfg))
    return policy, task, comm
