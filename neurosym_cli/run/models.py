"""What a baseline runs on, from its run directory: the communication provider its scheme (``cfg.baseline``,
schemes/) builds with its synthesized artifact (program or tree) loaded and checked against the task, and the
weights, checked against the task condition they were trained under and the memory the run will need."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..config import ConfigError, RunConfig
from ..policy.comm import CommProvider, comm_module, with_link_failure
from ..utils.io import ArtifactError
from .remake import missing_chain, retrain_command, train_command
from .layout import RunDir

if TYPE_CHECKING:
    from ..baselines import BaselineConfig


def scheme_provider(cfg: RunConfig, task=None, *, scheme: "BaselineConfig | None" = None) -> CommProvider:
    """The bare provider of ``scheme`` (default ``cfg.baseline``), its program or tree read from this run
    directory (or ``program=``); ``task``: the task, for a scheme whose rule needs it when built."""
    scheme = scheme or cfg.baseline
    file = RunDir(cfg).artifact_file(scheme)  # only a scheme that runs under a program or tree takes one
    if file is None:
        return scheme.provider(cfg, task)
    comm = scheme.provider(cfg, task, artifact=file)
    if scheme.has_program and not cfg.program:  # the run's own program: never without its search's summary
        from ..policy.protocol import unwrap
        from .summary import check_synthesized

        check_synthesized(file, unwrap(comm).program, scheme.command("synth", cfg))
    return comm


def baseline_comm(cfg: RunConfig, task=None, *, scheme: "BaselineConfig | None" = None) -> CommProvider:
    """The provider of ``scheme`` (default ``cfg.baseline``: a program or tree from the run directory or
    ``program=``, or a rule), with the task's link failure. ``task``: the task it runs on (built from the config
    when not given)."""
    if task is None:
        from ..tasks import make_task

        task = make_task(cfg.task, cfg.horizon)
    return with_link_failure(scheme_provider(cfg, task, scheme=scheme), cfg.task.link_failure)


def check_memory(cfg: RunConfig, task, comm: CommProvider, training: bool) -> None:
    """Refuse, in one line with the estimate and the largest team that fits, a run whose largest episode cannot fit
    in the memory available (policy/footprint.py), before anything is allocated. Evaluation batches every test
    episode of every seed with the same N; training ``budget.batch_rollouts`` episodes over the horizon."""
    from ..policy.footprint import require_fits

    n = cfg.task.max_agents
    per_seed = len(cfg.task.test_settings) or cfg.task.eval_episodes
    batch = cfg.budget.batch_rollouts if training else per_seed * cfg.budget.eval_seeds
    what = f"{cfg.baseline.name} {'training' if training else 'evaluation'}"
    require_fits(what, n, batch=batch, horizon=cfg.horizon, rounds=task.rounds, model=cfg.model, k=cfg.rules,
                 dense=not comm.picks_first, training=training, sparse_from=getattr(cfg.task, "sparse_from", 1 << 62))


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
    return cfg.baseline.artifact_identity(cfg, comm, artifact=RunDir(cfg).artifact_file())  # type: ignore[attr-defined]


PROTOCOL_KEYS = frozenset({"eval_episodes", "test_settings", "rules", "lam", "objective"})
"""task fields that choose the evaluation protocol or the search's defaults, not the condition a model acts in"""


def check_trained_condition(cfg: RunConfig, payload: dict, path) -> None:
    """Refuse to evaluate (or draw) a model under a task condition other than its training's: the result would be
    written where the trained condition's is (eval/<label>/) and read as it by `report` and the figures."""
    diff = cfg.first_difference(payload.get("config") or {}, ("task",), PROTOCOL_KEYS)
    if diff:
        key, old, new = diff
        raise ConfigError(f"{path} was trained with {key}={old!r}, this run has {new!r}: its results would replace "
                          f"those under the trained condition; leave {key} out, or train a model under it in its "
                          f"own runs root (`{train_command(cfg)} {key}={new} runs_root=...`)")


def load_baseline(cfg: RunConfig, device, task=None) -> tuple[Any, Any, CommProvider]:
    """(policy on ``device``, task, provider) of ``cfg.baseline``: its trained weights and its communication, on
    ``task`` (built from the config when not given). A partly trained model is used with a warning naming the
    command that finishes it."""
    from ..tasks import make_task
    from ..utils.console import log
    from .checkpoints import open_checkpoint, policy_from_payload

    if cfg.program and not cfg.baseline.has_program:  # it would be ignored, and the result filed as the baseline's
        from ..schemes import SCHEMES

        raise ConfigError(f"program= is for the baselines that run under a program "
                          f"({', '.join(n for n, b in SCHEMES.items() if b.has_program)}); {cfg.baseline.name} runs "
                          "under none: leave program= out")
    chain = missing_chain(cfg)  # every stage not run yet at once, not the one just before
    if chain:
        raise ArtifactError(chain)
    model_file = RunDir(cfg).model_file
    payload = open_checkpoint(cfg)
    if task is None:  # the run's own task: it must be the one trained on (`stress` varies it on purpose)
        check_trained_condition(cfg, payload, model_file)
    if not payload.get("done"):
        log.warning("the model is only partly trained (step %d); using it anyway; `%s` finishes it",
                    payload["fit"]["step"], train_command(cfg))
    policy = policy_from_payload(payload).to(device)
    task = task or make_task(cfg.task, cfg.horizon)
    comm = baseline_comm(cfg, task)
    check_memory(cfg, task, comm, training=False)
    load_gate(comm, payload, model_file, train_command(cfg))
    if (gate := comm_module(comm)) is not None:
        gate.to(device)
    if payload.get("made_under") and payload["made_under"] != comm_identity(cfg, comm):
        log.warning("the retrained model was made under another program (or tree) than the one there now; "
                    "`%s overwrite=true` retrains it under this one", retrain_command(cfg))
    return policy, task, comm
