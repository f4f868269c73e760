"""What a baseline is, as an interface (stdlib only, so `neurosym --help` stays fast; imports nothing of the package).

A baseline is the shared transformer plus a communication scheme: the weights it runs on and the provider that
hands it a mask each round (paper section 4). Each baseline is a typed config schema, a subclass of
``BaselineConfig`` in ``schemes/`` registered once in ``schemes.SCHEMES``; the composed ``cfg.baseline`` *is* that
object, so every layer asks it instead of testing names: ``run/`` its directories and commands, the stage
graph its upstream stages, the stages its provider and artifact, the tables its label.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from .errors import check_finite

if TYPE_CHECKING:  # for annotations only: config.py imports this module
    from .config import RunConfig

ORACLE = "tf-full"
"""the baseline whose training makes the oracle that hard-attn, the programs, the trees and retraining start from"""

VERBS = ("train", "synth", "retrain", "eval")
"""the verbs of the stage graph"""


@dataclass(frozen=True)
class Stage:
    """One command of the stage graph: ``neurosym <verb> baseline=<baseline>``."""

    verb: str  # train, synth, retrain or eval
    baseline: str  # the baseline whose config the command runs with

    @property
    def name(self) -> str:
        return f"{self.verb} {self.baseline}"


@dataclass(frozen=True)
class Artifact:
    """What `neurosym synth` writes for a scheme: <exp_dir>/synth/<tag>/<file>."""

    tag: str  # the search's name: K, lambda, feature map and search variant (k2-lam0.5-v1, det-..., dt-k2-v1)
    file: str  # program.txt (a program in the paper's notation) or tree.json (a decision tree per round)


def runs_root_arg(cfg: "RunConfig") -> str:
    """`` runs_root=...`` when ``cfg``'s runs root is not the one the environment gives a new command (NEUROSYM_RUNS,
    else outputs), else "": a printed command must find the same run directory."""
    import os
    import shlex

    same = str(cfg.runs_root) == os.environ.get("NEUROSYM_RUNS", "outputs")
    return "" if same else " " + shlex.quote(f"runs_root={cfg.runs_root}")


def run_args(cfg: "RunConfig", seed: bool = True) -> str:
    """``task=... budget=... seed=...`` (and the runs root where needed) of ``cfg``: what every printed command
    carries, so it runs as printed whatever defaults (defaults.py) the next shell has."""
    return (f"task={cfg.task.name} budget={cfg.budget.name}" + (f" seed={cfg.seed}" if seed else "")
            + runs_root_arg(cfg))


def train_line(cfg: "RunConfig", baseline: str, extra: str = "") -> str:
    """`neurosym train` of ``baseline`` on ``cfg``'s task, budget and seed, then ``extra`` overrides."""
    return (f"neurosym train task={cfg.task.name} baseline={baseline} budget={cfg.budget.name} "
            f"seed={cfg.seed}{runs_root_arg(cfg)}{extra}")


@dataclass
class BaselineConfig:
    """A baseline = which weights run and which communication scheme decides the mask (paper section 4). The
    fields are what every baseline's schema has; a scheme adds its own (``baseline.det``, ``baseline.radius``)."""

    name: str = "???"  # OmegaConf's marker for a mandatory value
    description: str = ""
    pipeline: bool = True
    """made and evaluated by `neurosym pipeline` unless baselines= says otherwise"""

    has_program: ClassVar[bool] = False
    """runs under a program in the paper's notation (show-program reads it)"""
    soft_attention: ClassVar[bool] = False
    """hears every other agent with soft attention weights (tables say "all", pictures draw weights as opacity)"""

    def __post_init__(self) -> None:
        check_finite(self, "baseline.")  # a scheme's own numbers (baseline.radius, ...)

    def label(self, cfg: "RunConfig") -> str:
        """Name of its evaluation directory and its row in the tables (k, a program's tag, where they matter)."""
        return self.name

    def model_dir(self, cfg: "RunConfig") -> str:
        """Directory under <exp_dir>/train/ of the weights it runs on."""
        raise NotImplementedError

    def weights(self) -> Stage:
        """The stage that makes the weights it runs on."""
        raise NotImplementedError

    def artifact(self, cfg: "RunConfig") -> Artifact | None:
        """The synthesized artifact it runs under (program or tree), or None."""
        return None

    def upstream(self) -> list[Stage]:
        """Every stage that makes what its evaluation needs, in dependency order."""
        raise NotImplementedError

    def requires(self, verb: str) -> tuple[Stage, ...]:
        """The stages its own stage ``verb`` (train, synth or retrain; one of ``upstream()``) waits for."""
        return ()

    def command(self, verb: str, cfg: "RunConfig") -> str:
        """The command line of its stage ``verb`` on ``cfg`` (what error messages tell the user to run)."""
        raise NotImplementedError

    def claims(self, model_dir: str) -> int:
        """How specifically a train/ directory name is one of its models: the length of the matched name, 0 when
        it is not (the report names a training curve by the scheme that claims it longest)."""
        return 0

    def provider(self, cfg: "RunConfig", env: Any = None) -> Any:
        """Its communication provider (policy/comm.py ``CommProvider``) for ``cfg``, artifact loaded and checked;
        ``env``, the task, for a scheme whose rule needs it when built (none of the paper's). A scheme with an
        ``artifact(cfg)`` is also given its file as ``artifact=`` (a Path, composed by run/layout.py)."""
        raise NotImplementedError

    def rules(self, cfg: "RunConfig", comm: Any) -> int:
        """K of its results (metrics.json's ``rules``): the rules per round it ran under; the config's K unless its
        provider says otherwise (a hand-written program has its own)."""
        return cfg.rules

    def trains_from_oracle(self, cfg: "RunConfig") -> bool:
        """Its own model starts from the oracle's weights (for budget.retrain_rollouts at optim.retrain_lr)."""
        return False

    def weights_command(self, cfg: "RunConfig") -> str:
        """The command line that makes the weights it runs on."""
        w = self.weights()
        return train_line(cfg, ORACLE) if w.baseline != self.name else self.command(w.verb, cfg)
