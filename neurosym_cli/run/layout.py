"""Where every artifact of an experiment lives, named once (stdlib only). The names inside come from the baseline's
scheme (``cfg.baseline``, schemes/): its model directory, its artifact's tag and file, its label; this module
composes them into paths, the schemes never do.

    <exp_dir>/train/<model>/              model.pt, history.csv, manifest.json
    <exp_dir>/synth/dataset-r<R>-s<S>.pt  the oracle dataset D, shared by every synthesis run of this oracle
    <exp_dir>/synth/<artifact tag>/       program.txt or tree.json, summary.json, trace.csv
    <exp_dir>/eval/<baseline label>/      metrics.json, metrics.csv
    <exp_dir>/render/<baseline label>/    animations and episode pictures
    <exp_dir>/figures/                    the paper's figures
    <exp_dir>/tensorboard/<run>/          event files (logger=tensorboard)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..config import ConfigError

if TYPE_CHECKING:
    from ..baselines import BaselineConfig
    from ..config import RunConfig

TRAIN, SYNTH, EVAL = "train", "synth", "eval"
"""the stages' folders under <exp_dir>"""
ORACLE_DIR = "oracle"
"""train/<this>: the oracle's weights (tf-full's model directory), which hard-attn, the searches and retraining
start from"""
MODEL, HISTORY, MANIFEST = "model.pt", "history.csv", "manifest.json"
"""a training's checkpoint, its loss per step, and its record (train/<model>/)"""
SUMMARY = "summary.json"
"""a search's record beside its program or tree (synth/<tag>/)"""
METRICS, METRICS_CSV = "metrics.json", "metrics.csv"
"""an evaluation's summary and its per-seed rows (eval/<label>/)"""


@dataclass(frozen=True)
class RunDir:
    """The artifacts of ``cfg``'s run directory (``cfg.exp_dir``) for ``cfg``'s baseline."""

    cfg: "RunConfig"

    @property
    def root(self) -> Path:
        return Path(self.cfg.exp_dir)

    # ------------------------------------------------------------------------------------------ names
    @property
    def model_name(self) -> str:
        """Directory name of the weights the baseline uses: the shared oracle, its own model, or a retraining."""
        return self.cfg.baseline.model_dir(self.cfg)

    @property
    def program_tag(self) -> str:
        """Name of one synthesis result: det- for argmax-only programs, K, lambda, feature map, and how the search
        differs from the default (dt: K, features); a hand-written program is named by file and content."""
        artifact = self.cfg.baseline.artifact(self.cfg)
        if artifact is None:
            raise ConfigError(f"baseline {self.cfg.baseline.name} runs under no program or tree")
        return artifact.tag

    @property
    def label(self) -> str:
        """Name of the baseline's evaluation directory (k, and the program's tag, where they matter)."""
        return self.cfg.baseline.label(self.cfg)

    # ------------------------------------------------------------------------------------------ train
    @property
    def train_dir(self) -> Path:
        return self.root / TRAIN / self.model_name

    @property
    def model_file(self) -> Path:
        """The checkpoint of the weights the baseline runs on."""
        return self.train_dir / MODEL

    @property
    def history_file(self) -> Path:
        return self.train_dir / HISTORY

    @property
    def manifest_file(self) -> Path:
        return self.train_dir / MANIFEST

    @property
    def oracle_file(self) -> Path:
        """The oracle's checkpoint, whatever the baseline."""
        return self.root / TRAIN / ORACLE_DIR / MODEL

    # ------------------------------------------------------------------------------------------ synth
    @property
    def synth_dir(self) -> Path:
        return self.root / SYNTH / self.program_tag

    def artifact_file(self, scheme: "BaselineConfig | None" = None) -> Path | None:
        """The file of the program or tree ``scheme`` (default: the baseline) runs under: ``program=`` for a scheme
        that runs under a program, else synth/<tag>/<file>; None for a scheme that runs under neither."""
        scheme = scheme or self.cfg.baseline
        artifact = scheme.artifact(self.cfg)
        if artifact is None:
            return None
        if self.cfg.program and scheme.has_program:
            return Path(self.cfg.program)
        return self.root / SYNTH / artifact.tag / artifact.file

    @property
    def program_file(self) -> Path:
        """The program the baseline runs under: ``program=`` or the synthesized one."""
        if self.cfg.program:
            return Path(self.cfg.program)
        if not self.cfg.baseline.has_program:
            raise ConfigError(f"baseline {self.cfg.baseline.name} runs under no program")
        return self.synthesized_file

    @property
    def synthesized_file(self) -> Path:
        """What `neurosym synth` writes for the baseline, ``program=`` aside: synth/<tag>/<program.txt or
        tree.json>."""
        return self.synth_dir / self.cfg.baseline.artifact(self.cfg).file

    @property
    def summary_file(self) -> Path:
        return self.synth_dir / SUMMARY

    @property
    def trace_file(self) -> Path:
        """A program search's objective per step (synth/<tag>/trace.csv)."""
        return self.synth_dir / "trace.csv"

    @property
    def dataset_file(self) -> Path:
        """The oracle's dataset D, shared by every search with the same rollouts and stride."""
        return self.root / SYNTH / f"dataset-r{self.cfg.budget.synth_rollouts}-s{self.cfg.synth.stride}.pt"

    def summaries(self, stem: str) -> list[Path]:
        """summary.json of every synthesis result whose tag starts with ``stem``, sorted."""
        return sorted((self.root / SYNTH).glob(f"{stem}*/{SUMMARY}"))

    # ------------------------------------------------------------------------------------------ eval
    @property
    def eval_root(self) -> Path:
        """Where every baseline's evaluation directory is (and the report's figures)."""
        return self.root / EVAL

    def eval_dir(self, label: str | None = None) -> Path:
        """eval/<label>/, the baseline's label by default."""
        return self.eval_root / (label or self.label)

    # ------------------------------------------------------------------------------------------ pictures, logs
    @property
    def render_dir(self) -> Path:
        """Animations and episode pictures of the baseline (`neurosym render`)."""
        return self.root / "render" / self.label

    @property
    def figures_dir(self) -> Path:
        """The paper's figures drawn from this run directory (`neurosym figures`)."""
        return self.root / "figures"

    def tensorboard_dir(self, run: str) -> Path:
        """TensorBoard event files of one run of this experiment (logger=tensorboard), e.g. run = "train-oracle"."""
        return self.root / "tensorboard" / run


def metrics_files(exp_dir: Path) -> list[Path]:
    """metrics.json of every baseline evaluated in the run directory ``exp_dir``, sorted."""
    return sorted((Path(exp_dir) / EVAL).glob(f"*/{METRICS}"))


def history_files(root: Path) -> list[Path]:
    """history.csv of every model trained under ``root``: a runs folder of seed directories, or one run directory."""
    return (sorted(Path(root).glob(f"seed*/{TRAIN}/*/{HISTORY}"))
            or sorted(Path(root).glob(f"{TRAIN}/*/{HISTORY}")))
