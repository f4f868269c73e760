"""Policy checkpoints: a self-describing format (weights, architecture, config, resume state), written atomically and
loaded safely (``weights_only=True``: tensors and plain data, never arbitrary pickles). ``open_checkpoint`` opens the
oracle's or a baseline's own checkpoint of a run directory in one call, naming the command that makes it."""

from __future__ import annotations

import io
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import torch

from ..config import ModelConfig, UserError
from ..errors import cut
from ..policy.transformer import CommTransformer
from ..utils.cpu import runtime
from ..utils.io import ArtifactError, atomic_write_bytes
from .remake import train_command
from .layout import RunDir

if TYPE_CHECKING:
    from ..config import RunConfig

CHECKPOINT_FORMAT = "neurosym-policy/1"


# ------------------------------------------------------------------------------------------ resume modes
def _at(payload: dict[str, Any], *keys: str) -> Any:
    """payload[k1][k2]..., None where a level is missing or not a dict (a checkpoint from before the key)."""
    for k in keys:
        payload = payload.get(k) if isinstance(payload, dict) else None
    return payload


def _as_stepped(mode: str, cfg: "RunConfig") -> str:
    """A compile mode as the steps ran it: fused on a task whose teams never reach the kernels' FUSED_FROM agents ran
    the eager round throughout (the kernels served no round), so it counts as off."""
    from ..policy.edge_kernels import FUSED_FROM

    most = getattr(cfg.task, "max_agents", None)  # None: a config without its task's schema (Python, tests)
    return "off" if mode == "fused" and isinstance(most, int) and most < FUSED_FROM else mode


def _compiled_now(cfg: "RunConfig") -> str:
    from ..utils.compiling import in_effect

    return _as_stepped(in_effect(), cfg)  # compile=auto is off; on where it compiles; fused where the kernels run


@dataclass(frozen=True)
class ResumeMode:
    """A setting a checkpoint resumes under only as it was trained: steps under two values would be a run neither
    makes (other kernels, or a compiled step, round differently), recorded as the last value only."""

    key: str
    """the setting's name on the command line"""
    recorded: Callable[[dict[str, Any], "RunConfig"], Any]
    """its value in a checkpoint's payload (of this run's config); None: not recorded (a checkpoint from before the
    key), any value resumes"""
    current: Callable[["RunConfig"], Any]
    """its value in this run"""


RESUME_MODES = (
    ResumeMode("cpu_kernels", lambda p, cfg: _at(p, "config", "cpu_kernels"), lambda cfg: cfg.cpu_kernels),
    # the step as it ran (in effect), not as asked; a checkpoint from before the key ran eager
    ResumeMode("compile", lambda p, cfg: _as_stepped(_at(p, "runtime", "compile", "in_effect") or "off", cfg),
               _compiled_now),
)
"""every setting a resume must keep"""


def refuse_other_modes(payload: dict[str, Any], ckpt: object, *, steps: int, cfg: "RunConfig") -> None:
    """One line (ConfigError) when ``cfg`` differs from the checkpoint in a setting of RESUME_MODES."""
    from ..errors import ConfigError

    for mode in RESUME_MODES:
        was, now = mode.recorded(payload, cfg), mode.current(cfg)
        if was is not None and was != now:
            raise ConfigError(f"{ckpt} was trained for {steps} steps under {mode.key}={was}, this run has "
                              f"{mode.key}={now}: resume it with {mode.key}={was}, or pass overwrite=true to train "
                              "it from the start under this one")


def checkpoint_bytes(payload: dict[str, Any]) -> bytes:
    """The bytes of a torch file holding ``payload`` (written by the caller, atomically, with its siblings)."""
    buf = io.BytesIO()
    torch.save(payload, buf)
    return buf.getvalue()


def save_checkpoint(path: Path, payload: dict[str, Any]) -> None:
    """Write ``payload`` to ``path`` atomically (a reader sees the old file or the new one, never half of one)."""
    atomic_write_bytes(Path(path), checkpoint_bytes(payload))


def load_payload(path: Path, made_by: str, fmt: str, what: str) -> dict[str, Any]:
    """Load a torch file of format ``fmt`` safely (``weights_only=True``: tensors and plain data, never arbitrary
    pickles); ``made_by`` is the command that creates it, named in the one-line error."""
    path = Path(path)
    if not path.exists():
        raise ArtifactError(f"no {what} at {path}; create it with `{made_by}`")
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # truncated file, foreign pickle, wrong format: all the same to the user
        raise ArtifactError(f"corrupt {what} {path} ({type(e).__name__}); delete it and re-run `{made_by}`") from None
    if not isinstance(payload, dict) or payload.get("format") != fmt:
        raise ArtifactError(f"{path} is not a {fmt} file; re-run `{made_by}`")
    return payload


def non_finite(obj: Any, where: str = "") -> str | None:
    """Where the first nan or inf of a payload's float tensors is (``where`` + its keys and indices, as
    ``state_dict.w``, ``[0].rel``), or None: nested dicts, lists and tuples are searched."""
    if isinstance(obj, torch.Tensor):
        return where or "a tensor" if obj.is_floating_point() and not bool(torch.isfinite(obj).all()) else None
    items = obj.items() if isinstance(obj, dict) else enumerate(obj) if isinstance(obj, (list, tuple)) else ()
    for k, v in items:
        found = non_finite(v, f"{where}.{k}" if isinstance(k, str) else f"{where}[{k}]")
        if found:
            return found.lstrip(".")
    return None


def load_checkpoint(path: Path, made_by: str) -> dict[str, Any]:
    """A policy checkpoint (weights, architecture, config, resume state); one with a nan or inf weight (a
    diverged training, saved before training refused to save them) is refused: it would evaluate as nan."""
    payload = load_payload(path, made_by, CHECKPOINT_FORMAT, "checkpoint")
    why = _checkpoint_problem(payload)
    if why:  # the right format tag, but keys missing or weights of other shapes: never half-loaded
        raise ArtifactError(f"{path} is not a usable checkpoint: {why}; delete it and re-run `{made_by}`")
    bad = non_finite({part: payload.get(part) for part in ("state_dict", "comm_state")})
    if bad:
        raise ArtifactError(f"{path} holds non-finite weights ({bad}: a diverged training); re-run `{made_by}` "
                            "with overwrite=true and a smaller optim.lr")
    return payload


def open_checkpoint(cfg: "RunConfig", *, oracle: bool = False) -> dict[str, Any]:
    """The checkpoint of the weights ``cfg``'s baseline runs on (train/<model>/model.pt), or with ``oracle`` the
    oracle's (train/oracle/model.pt), checked whole; a missing or unusable one names the command that makes it."""
    run = RunDir(cfg)
    return load_checkpoint(run.oracle_file if oracle else run.model_file, train_command(cfg, oracle=oracle))


_CHECKPOINT_KEYS = (("state_dict", dict), ("arch", dict), ("config", dict), ("fit", dict), ("done", bool))
"""what every reader of a checkpoint takes from it (``policy_payload`` writes them)"""


def _checkpoint_problem(payload: dict[str, Any]) -> str | None:
    """Why a payload of the checkpoint format cannot be used (a key missing or of another type, weights that do
    not fit the architecture it records), or None. The model is built and loaded strictly to find out."""
    for key, typ in _CHECKPOINT_KEYS:
        if not isinstance(payload.get(key), typ):
            return f"{key!r} is missing or not a {typ.__name__}"
    fit = payload["fit"]
    if not (isinstance(fit.get("step"), int) and fit["step"] >= 0 and isinstance(fit.get("history"), list)):
        return "'fit' has no step count and history"
    try:
        policy_from_payload(payload)
    except (KeyError, TypeError, ValueError, RuntimeError, UserError) as e:
        lines = [ln.strip() for ln in str(e).splitlines() if ln.strip()]
        return f"its weights do not fit the architecture it records ({cut(' '.join(lines[1:2] or lines[:1]), 160)})"
    return None


# ------------------------------------------------------------------------------------------- policies
def policy_payload(policy: CommTransformer, model_cfg: ModelConfig, run_cfg: dict, fit: dict, done: bool) -> dict:
    """A self-describing checkpoint: the weights plus everything needed to rebuild and resume the model."""
    return {
        "format": CHECKPOINT_FORMAT,
        "state_dict": policy.state_dict(),
        "arch": {"obs_dim": policy.obs_dim, "pair_dim": policy.pair_dim, "action_dim": policy.action_dim,
                 "rounds": policy.n_rounds,
                 **asdict(model_cfg)},
        "config": run_cfg,
        "runtime": runtime(),  # the kernels it was trained with (utils/cpu.py)
        "fit": fit,
        "done": done,
    }


def policy_from_payload(payload: dict[str, Any]) -> CommTransformer:
    """The transformer a checkpoint records, its weights loaded (on the CPU)."""
    arch = dict(payload["arch"])
    model = CommTransformer(arch.pop("obs_dim"), arch.pop("action_dim"), arch.pop("rounds"), pair_dim=arch.pop("pair_dim", 2),
                            cfg=ModelConfig(**arch))  # checkpoints before pair_dim was recorded: 2
    model.load_state_dict(payload["state_dict"])
    return model
