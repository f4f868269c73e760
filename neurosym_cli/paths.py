"""Where every artifact of an experiment lives (stdlib only, so light commands need no torch). The names come from
the baseline's scheme (``cfg.baseline``, schemes/): its model directory, its artifact's tag, its label.

    <exp_dir>/train/<model>/            model.pt, history.csv, manifest.json
    <exp_dir>/synth/dataset-r<R>-s<S>.pt  the oracle dataset D, shared by every synthesis run of this oracle
    <exp_dir>/synth/<program tag>/      program.txt, summary.json, trace.csv
    <exp_dir>/eval/<baseline label>/    metrics.json, metrics.csv
"""

from __future__ import annotations

from pathlib import Path

from .baselines import ORACLE, train_line
from .config import ConfigError, RunConfig


def model_name(cfg: RunConfig) -> str:
    """Directory name of the weights a baseline uses: the shared oracle, its own trained model, or a retraining."""
    return cfg.baseline.model_dir(cfg)


def program_tag(cfg: RunConfig) -> str:
    """Name of one synthesis result: det- for argmax-only programs, K, lambda, feature map, and how the search
    differs from the default (dt: K, features); a hand-written program is named by file and content."""
    artifact = cfg.baseline.artifact(cfg)
    if artifact is None:
        raise ConfigError(f"baseline {cfg.baseline.name} runs under no program or tree")
    return artifact.tag


def baseline_label(cfg: RunConfig) -> str:
    """Name of a baseline's evaluation directory (k, and the program's tag, where they matter)."""
    return cfg.baseline.label(cfg)


def train_dir(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "train" / model_name(cfg)


def oracle_checkpoint(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "train" / "oracle" / "model.pt"


def synth_dir(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "synth" / program_tag(cfg)


def program_file(cfg: RunConfig) -> Path:
    return Path(cfg.program) if cfg.program else synth_dir(cfg) / "program.txt"


def tree_file(cfg: RunConfig) -> Path:
    return synth_dir(cfg) / "tree.json"



def dataset_file(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "synth" / f"dataset-r{cfg.budget.synth_rollouts}-s{cfg.synth.stride}.pt"


def render_dir(cfg: RunConfig) -> Path:
    """Animations and episode pictures of one baseline (`neurosym render`)."""
    return Path(cfg.exp_dir) / "render" / baseline_label(cfg)


def figures_dir(cfg: RunConfig) -> Path:
    """The paper's figures drawn from this run directory (`neurosym figures`)."""
    return Path(cfg.exp_dir) / "figures"


def tensorboard_dir(cfg: RunConfig, run: str) -> Path:
    """TensorBoard event files of one run of this experiment (logger=tensorboard), e.g. run = "train-oracle"."""
    return Path(cfg.exp_dir) / "tensorboard" / run


def eval_dir(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "eval" / baseline_label(cfg)


def train_command(cfg: RunConfig, oracle: bool = False) -> str:
    """The command line that makes the weights ``cfg``'s baseline needs (or the oracle's)."""
    return train_line(cfg, ORACLE) if oracle else cfg.baseline.weights_command(cfg)


def retrain_command(cfg: RunConfig) -> str:
    """The command line that retrains ``cfg``'s (retrained) baseline."""
    return cfg.baseline.command("retrain", cfg)


def synth_command(cfg: RunConfig) -> str:
    """The command line that synthesizes the program or tree ``cfg``'s baseline runs under."""
    return cfg.baseline.command("synth", cfg)


def pipeline_command(cfg: RunConfig) -> str:
    """The command line that makes (or reuses) every artifact of ``cfg``'s run directory and evaluates again."""
    return f"neurosym pipeline task={cfg.task.name} budget={cfg.budget.name} seed={cfg.seed}"
