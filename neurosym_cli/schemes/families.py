"""The three ways a baseline gets its weights, as the base classes of every scheme (stdlib at import).

    OnOracle   runs on the oracle's weights (tf-full, hard-attn, prog, dt): trained once, by `train baseline=tf-full`
    OwnModel   trains its own transformer under its own mask (dist, no-comm, rl, expo, comm-range)
    Retrained  the oracle fine-tuned under a synthesized artifact (prog-retrained, dt-retrained; paper section 3.5)

``OwnRule`` is an ``OwnModel`` that is its own provider (a ``policy.protocol.CommBase``): a new fixed rule is one
class that writes ``picks`` (the sparse path) or ``mask`` (the dense one), and one entry in ``schemes.SCHEMES``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..baselines import ORACLE, BaselineConfig, Stage, train_line
from ..errors import ConfigError
from ..policy.protocol import CommBase

if TYPE_CHECKING:
    from torch import Tensor

    from ..config import RunConfig
    from ..policy.comm import CommContext


def _train_only(b: BaselineConfig, verb: str) -> None:
    if verb != "train":
        raise ConfigError(f"{b.name} has no {verb} stage: it needs only trained weights")


@dataclass
class OnOracle(BaselineConfig):
    """Runs on the oracle's weights: its `train` stage is the oracle's (tf-full under full soft attention)."""

    def model_dir(self, cfg: "RunConfig") -> str:
        return "oracle"

    def weights(self) -> Stage:
        return Stage("train", ORACLE)

    def upstream(self) -> list[Stage]:
        return [self.weights()]

    def command(self, verb: str, cfg: "RunConfig") -> str:
        _train_only(self, verb)
        return train_line(cfg, ORACLE)

    def claims(self, model_dir: str) -> int:
        return len(model_dir) if model_dir == "oracle" else 0


@dataclass
class OwnModel(BaselineConfig):
    """Trains a transformer of its own under its own mask (`neurosym train baseline=<name>`): its weights live in
    train/<name>[-<tag>]/ and its label is the same name."""

    def tag(self, cfg: "RunConfig") -> str:
        """What tells two of its models apart in their directory name (k2, r1.5, ...); empty when nothing does."""
        return ""

    def train_overrides(self, cfg: "RunConfig") -> str:
        """The overrides its `train` command line needs to make the model of ``tag(cfg)`` (" rules=2", ...)."""
        return ""

    def model_dir(self, cfg: "RunConfig") -> str:
        tag = self.tag(cfg)
        return f"{self.name}-{tag}" if tag else self.name

    def label(self, cfg: "RunConfig") -> str:
        return self.model_dir(cfg)

    def weights(self) -> Stage:
        return Stage("train", self.name)

    def upstream(self) -> list[Stage]:
        return [*self.requires("train"), self.weights()]

    def command(self, verb: str, cfg: "RunConfig") -> str:
        _train_only(self, verb)
        return train_line(cfg, self.name, self.train_overrides(cfg))

    def claims(self, model_dir: str) -> int:
        return len(self.name) if model_dir == self.name or model_dir.startswith(self.name + "-") else 0


@dataclass
class OwnRule(OwnModel, CommBase):
    """An ``OwnModel`` whose mask is a fixed rule of the step's context: the scheme is its own provider. Write
    ``picks`` (B, N, K) long, -1 = nobody: the transformer then computes the K picked pairs only (the sparse path,
    policy/transformer.py); or ``mask`` (B, N, N) bool, self excluded, and leave ``picks`` None (the dense path)."""

    def provider(self, cfg: "RunConfig", env: Any = None) -> "OwnRule":
        return self

    def mask(self, ctx: "CommContext", round: int) -> "Tensor":
        """(B, N, N) bool, i hears j, self excluded: the dense rule; by default the picks as a mask."""
        return CommBase.select(self, ctx, None, round)  # type: ignore[arg-type]  (CommBase's reads no logits)

    def select(self, ctx: "CommContext", logits: "Tensor", round: int) -> "Tensor":
        """The provider's dense answer (policy/protocol.py): its mask, whatever the logits."""
        return self.mask(ctx, round)


def rate_suffix(cfg: "RunConfig") -> str:
    """'-rlr<rate>' when a retraining starts at another rate than optim.retrain_lr's default (`neurosym tune`
    searches the rate), else '': models retrained at two rates never share a directory, label or validation file,
    and the default's names are those of every earlier run."""
    from ..config import OptimConfig

    lr = cfg.optim.retrain_lr
    return "" if lr == OptimConfig.retrain_lr else f"-rlr{lr:g}"


class Retrained:
    """Mixin for the oracle retrained under a synthesized artifact (`neurosym retrain`, paper section 3.5): put it
    before the artifact's scheme class. Its weights live in train/retrained-<artifact tag>[-rlr<rate>]/."""

    def model_dir(self, cfg: "RunConfig") -> str:
        return f"retrained-{self.artifact(cfg).tag}{rate_suffix(cfg)}"  # type: ignore[attr-defined]

    def label(self, cfg: "RunConfig") -> str:
        return super().label(cfg) + rate_suffix(cfg)  # type: ignore[misc]

    def command(self, verb: str, cfg: "RunConfig") -> str:
        line = super().command(verb, cfg)  # type: ignore[misc]
        return line + (f" optim.retrain_lr={cfg.optim.retrain_lr:g}" if verb == "retrain" and rate_suffix(cfg)
                       else "")

    def weights(self) -> Stage:
        return Stage("retrain", self.name)  # type: ignore[attr-defined]

    def upstream(self) -> list[Stage]:
        return [Stage("train", ORACLE), *self.requires("retrain"), self.weights()]

    def requires(self, verb: str) -> tuple[Stage, ...]:
        return (Stage("synth", self.search()),) if verb == "retrain" else ()  # type: ignore[attr-defined]

    def claims(self, model_dir: str) -> int:
        prefix = "retrained-" + self.tag_prefix()  # type: ignore[attr-defined]
        return len(prefix) if model_dir.startswith(prefix) else 0
