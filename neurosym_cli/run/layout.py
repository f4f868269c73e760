"""Where every artifact of an experiment lives, named once (stdlib only). The names inside come from the baseline's
scheme (``cfg.baseline``, schemes/): its model directory, its artifact's tag and file, its label; this module
composes them into paths, the schemes never do.

    <exp_dir>/train/<model>/              model.pt, history.csv, manifest.json
    <exp_dir>/synth/dataset-r<R>-s<S>.pt  the oracle dataset D, shared by every synthesis run of this oracle
    <exp_dir>/synth/<artifact tag>/       program.txt or tree.json, summary.json, trace.csv (front.json/.csv)
    <exp_dir>/eval/<baseline label>/      metrics.json, metrics.csv
    <exp_dir>/render/<baseline label>/    animations and episode pictures
    <exp_dir>/figures/                    the paper's figures
    <exp_dir>/tensorboard/<run>/          event files (logger=tensorboard)
    <exp_dir>/pipeline_timings.json       each stage's wall time (`neurosym pipeline`)
    <exp_dir>/select/                     selected.json, selection.json/.csv, val/<label>.json (`neurosym select`)
    <exp_dir>/select/front/               <tag>.json, <tag>-b<budget>.txt, <tag>-near<budget>.txt (pipeline.select=front)
    <exp_dir>/select/tune/                optuna.db, <study>/selection.json/.csv, pareto.csv/.png (`neurosym tune`)
    <exp_dir>/rl/                         picks.json, grid.json/.csv (`neurosym rl`)
    <exp_dir>/stress/                     stress.json/.csv/.png (`neurosym stress`)
    <exp_dir>/export/<baseline label>/    an export folder, its record manifest.json (`neurosym export`)

Run directories sit in a runs root as <runs_root>/<task>[-fail<p>]/<budget>/seed<k>/ (the config's exp_dir);
``RunsRoot(runs_root)`` finds their evaluations and reads the task and link failure back from a folder's name.
Above the run directories, `neurosym report` writes its files into <runs_root>/<task>/<budget>/ (``REPORT_*``).

``RunFolder(exp_dir)`` finds what a finished run directory holds by its path alone (reports, benchmarks);
``RunDir(cfg)`` adds what depends on the config's baseline.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..config import ConfigError

if TYPE_CHECKING:
    from ..baselines import BaselineConfig
    from ..config import RunConfig

TRAIN, SYNTH, EVAL = "train", "synth", "eval"
"""the stages' folders under <exp_dir>"""
SELECT, RL, STRESS = "select", "rl", "stress"
"""the grid and stress verbs' folders under <exp_dir>"""
RENDER, FIGURES, TENSORBOARD, EXPORT = "render", "figures", "tensorboard", "export"
"""the folders of pictures, logs and exports under <exp_dir>"""
ORACLE_DIR = "oracle"
"""train/<this>: the oracle's weights (tf-full's model directory), which hard-attn, the searches and retraining
start from"""
MODEL, HISTORY, MANIFEST = "model.pt", "history.csv", "manifest.json"
"""a training's checkpoint, its loss per step, and its record (train/<model>/)"""
PROGRAM, TREE = "program.txt", "tree.json"
"""the files a search writes (synth/<tag>/): a program, or decision trees (the scheme says which)"""
SUMMARY, TRACE = "summary.json", "trace.csv"
"""a search's record beside its program or tree, and its objective per step (synth/<tag>/)"""
FRONT = "front.json"
"""a search's degree-budget front (synth/<tag>/, synth.front=true; front.csv beside it)"""
METRICS_FILE, METRICS_CSV = "metrics.json", "metrics.csv"
"""an evaluation's summary and its per-seed rows (eval/<label>/)"""
SELECTED, SELECTION, VAL = "selected.json", "selection", "val"
"""select/: the choice, the whole selection (.json, .csv), and the validation rows per label (val/<label>.json)"""
FRONT_SELECT = "front"
"""select/front/: the pipeline's choice among a search's degree-budget front and its candidates' program files"""
TUNE, TUNE_DB = "tune", "optuna.db"
"""select/tune/: `neurosym tune`'s default study storage (SQLite) and one folder per study (its table and front)"""
PICKS, GRID = "picks.json", "grid"
"""rl/: the picks rl1 and rl2, and every setting (.json, .csv)"""
TIMINGS = "pipeline_timings.json"
"""<exp_dir>/: the wall time of each stage of `neurosym pipeline`"""
STRESS_STEM = "stress"
"""stress/stress.json, .csv and .png"""
EXPORT_MANIFEST = MANIFEST
"""an export folder's record, which marks it as one (export/folder.py; the standalone check reads the same name)"""
SEED_PREFIX, FAIL_INFIX = "seed", "-fail"
"""a training seed's run directory is seed<k>; a link-failure run's task folder is <task>-fail<p>"""
_TASK_DIR = re.compile(r"(.+?)(?:" + FAIL_INFIX + r"([0-9.e-]+))?")
_SEED_DIR = re.compile(SEED_PREFIX + r"(\d+)")

# the files `neurosym eval`'s table draws into eval/ (stages/results.write_figure)
FIGURE2, CURVES = "figure2.png", "curves.png"
"""eval/: every baseline evaluated in the run directory as a Figure-2-style plot, and the training curves"""
# the files `neurosym report` writes into <runs_root>/<task>/<budget>/ (stages/results.report; benchmarks read them)
REPORT_JSON, REPORT_CSV, IMPROVEMENT_CSV = "report.json", "report.csv", "improvement.csv"
"""the across-seed statistics per task (JSON; CSV long: task, baseline, metric, ...) and the probability of
improvement over training seeds"""
REPORT_MARL_EVAL = "report_marl_eval.json"
"""the across-seed rows in marl-eval's raw layout"""
REPORT_PNG, REPORT_CURVES = "report.png", "report_curves.png"
"""the across-seed Figure-2-style plot and the training curves of every seed"""
PARETO_CSV, PARETO_PNG = "pareto.csv", "pareto.png"
"""loss against max degree of every baseline, its non-dominated set and dominated area"""
SEEDS_PROFILE = "seeds-profile.png"
"""the performance profile of normalized loss over tasks and training seeds (seeds/figures.draw)"""


def seed_dir(seed: int) -> str:
    """seed<k>: the run directory of training seed k under <runs_root>/<task dir>/<budget>/."""
    return f"{SEED_PREFIX}{seed}"


def seeds_plane_file(task: str) -> str:
    """seeds-<task>.png: one task's baselines in the loss-degree plane over training seeds (seeds/figures.draw)."""
    return f"seeds-{task}.png"


def fail_suffix(p: float) -> str:
    """What follows the task's name in a link-failure run's task folder: -fail<p> (nothing at p = 0)."""
    return f"{FAIL_INFIX}{float(p):g}" if float(p) > 0 else ""


# the files `neurosym render` writes into render/<label>/ (stages/render.render_episode)
def episode_stem(episode: int, window: "list[float] | tuple[float, ...] | None" = None) -> str:
    """episode<k>, or episode<k>-window<x0>_<x1>_<y0>_<y1> for a zoom (so a zoom never replaces the whole
    picture): the animation is <stem>.gif (or .mp4), the whole episode <stem>.png, four frames ``frames_file``."""
    return f"episode{episode}" + ("" if window is None else "-window" + "_".join(f"{v:g}" for v in window))


def frames_file(stem: str) -> str:
    """<stem>-frames.png: four frames of an episode's animation."""
    return f"{stem}-frames.png"


# the pictures `neurosym figures` draws into figures/ (stages/render.make_figures), named after the program they show
ATTENTION, TRAJECTORIES, FIGURE1, RULES, FIGURE5 = "attention", "trajectories", "figure1", "rules", "figure5"
"""attention maps side by side, group paths, the paper's Figure 1, a program's rule regions, Figure 5"""


def figure_name(kind: str, tag: str, *, episode: int | None = None, round_: int | None = None) -> str:
    """<kind>-<tag>[-episode<k>][-round<r>].png: one of `neurosym figures`' pictures of program <tag>."""
    return (f"{kind}-{tag}" + ("" if episode is None else f"-episode{episode}")
            + ("" if round_ is None else f"-round{round_}") + ".png")


class _Folder:
    """The paths of a run directory that need no config: what ``RunFolder`` and ``RunDir`` share."""

    root: Path

    # ------------------------------------------------------------------------------------------ train, synth
    def trained_dir(self, model: str) -> Path:
        """train/<model>/, the weights of one model (``ORACLE_DIR`` for the oracle's)."""
        return self.root / TRAIN / model

    def manifest_of(self, model: str) -> Path:
        """train/<model>/manifest.json, one training's record."""
        return self.trained_dir(model) / MANIFEST

    def history_of(self, model: str) -> Path:
        """train/<model>/history.csv, one training's loss per step."""
        return self.trained_dir(model) / HISTORY

    def manifests(self) -> list[Path]:
        """manifest.json of every model trained here, sorted."""
        return sorted((self.root / TRAIN).glob(f"*/{MANIFEST}"))

    def synthesized_as(self, tag: str, file: str = PROGRAM) -> Path:
        """synth/<tag>/<file>, one search's program (or ``file``: its tree)."""
        return self.root / SYNTH / tag / file

    def datasets(self) -> list[Path]:
        """Every oracle dataset D collected here (synth/dataset-r<R>-s<S>.pt), sorted."""
        return sorted((self.root / SYNTH).glob("dataset-*.pt"))

    def programs(self) -> list[Path]:
        """program.txt of every search made here, sorted."""
        return sorted((self.root / SYNTH).glob(f"*/{PROGRAM}"))

    @property
    def timings_file(self) -> Path:
        """pipeline_timings.json: each stage's wall time, in seconds, as `neurosym pipeline` kept it."""
        return self.root / TIMINGS

    # ------------------------------------------------------------------------------------------ eval
    @property
    def eval_root(self) -> Path:
        """Where every baseline's evaluation directory is (and the report's figures)."""
        return self.root / EVAL

    def metrics_of(self, label: str) -> Path:
        """eval/<label>/metrics.json, one baseline's evaluation."""
        return self.eval_root / label / METRICS_FILE

    def metrics_files(self, labels: str = "*") -> list[Path]:
        """metrics.json of every baseline evaluated here whose label matches the glob ``labels``, sorted."""
        return sorted(self.eval_root.glob(f"{labels}/{METRICS_FILE}"))

    # ------------------------------------------------------------------------------------------ select, rl, stress
    @property
    def select_dir(self) -> Path:
        return self.root / SELECT

    @property
    def selected_file(self) -> Path:
        """select/selected.json: the choice of `neurosym select` (rules, lam, features, search settings)."""
        return self.select_dir / SELECTED

    def selection_file(self, suffix: str = ".json") -> Path:
        """select/selection.json (or .csv): every configuration of the selection and the pick's test rows."""
        return self.select_dir / (SELECTION + suffix)

    def val_file(self, label: str) -> Path:
        """select/val/<label>.json: one baseline's rows on the validation seeds."""
        return self.select_dir / VAL / f"{label}.json"

    def front_choice_file(self, tag: str) -> Path:
        """select/front/<tag>.json: the choice among search <tag>'s front (pipeline.select=front), every candidate's
        validation rows beside it."""
        return self.select_dir / FRONT_SELECT / f"{tag}.json"

    def front_candidate_file(self, tag: str, name: str) -> Path:
        """select/front/<tag>-<name>.txt: one candidate of search <tag>'s front (name b<budget>, or near<budget> for
        the sparse end's nearest-within-r program), run as program= (its evaluation label and retrained model are
        named by its content, schemes/searched.user_program_tag)."""
        return self.select_dir / FRONT_SELECT / f"{tag}-{name}.txt"

    @property
    def tune_db(self) -> Path:
        """select/tune/optuna.db: the SQLite file of `neurosym tune`'s studies when tune.storage names none."""
        return self.select_dir / TUNE / TUNE_DB

    def study_dir(self, study: str) -> Path:
        """select/tune/<study>/: one study's selection.json/.csv and pareto.csv/.png (`neurosym tune`)."""
        return self.select_dir / TUNE / study

    def study_file(self, study: str, suffix: str = ".json") -> Path:
        """select/tune/<study>/selection.json (or .csv): the study's trials as select's table, and its pick."""
        return self.study_dir(study) / (SELECTION + suffix)

    @property
    def rl_dir(self) -> Path:
        return self.root / RL

    @property
    def picks_file(self) -> Path:
        """rl/picks.json: rl1 and rl2 as `neurosym rl` picked them."""
        return self.rl_dir / PICKS

    def rl_grid_file(self, suffix: str = ".json") -> Path:
        """rl/grid.json (or .csv): every rl setting and the picks' test rows."""
        return self.rl_dir / (GRID + suffix)

    @property
    def stress_dir(self) -> Path:
        return self.root / STRESS

    def stress_file(self, suffix: str = ".json") -> Path:
        """stress/stress.json (or .csv, .png): every baseline at every condition of `neurosym stress`."""
        return self.stress_dir / (STRESS_STEM + suffix)

    # ------------------------------------------------------------------------------------------ pictures, logs
    @property
    def render_root(self) -> Path:
        """Where every baseline's animations are (render/<label>/)."""
        return self.root / RENDER

    @property
    def figures_dir(self) -> Path:
        """The paper's figures drawn from this run directory (`neurosym figures`)."""
        return self.root / FIGURES

    @property
    def figure2_file(self) -> Path:
        """eval/figure2.png: every baseline evaluated here (`neurosym eval`'s plot)."""
        return self.eval_root / FIGURE2

    @property
    def curves_file(self) -> Path:
        """eval/curves.png: the training curves of every model trained here."""
        return self.eval_root / CURVES

    def rendered(self, label: str, stem: str, suffix: str = ".gif") -> Path:
        """render/<label>/<stem><suffix>: one of `neurosym render`'s files (``episode_stem``)."""
        return self.render_root / label / f"{stem}{suffix}"

    def renders(self, stem: str, suffix: str = ".gif") -> list[Path]:
        """render/*/<stem><suffix> of every baseline rendered here, sorted."""
        return sorted(self.render_root.glob(f"*/{stem}{suffix}"))

    def figure_file(self, kind: str, tag: str, *, episode: int | None = None, round_: int | None = None) -> Path:
        """figures/<kind>-<tag>[-episode<k>][-round<r>].png (``figure_name``)."""
        return self.figures_dir / figure_name(kind, tag, episode=episode, round_=round_)

    def tensorboard_dir(self, run: str) -> Path:
        """TensorBoard event files of one run of this experiment (logger=tensorboard), e.g. run = "train-oracle"."""
        return self.root / TENSORBOARD / run


@dataclass(frozen=True)
class RunsRoot:
    """A folder of run directories, <root>/<task>[-fail<p>]/<budget>/seed<k>/, found by its path alone."""

    root: Path

    def __post_init__(self):
        object.__setattr__(self, "root", Path(self.root))

    def evaluations(self) -> list[Path]:
        """metrics.json of every evaluation of every run directory here
        (<task dir>/<budget>/seed<k>/eval/<label>/metrics.json), sorted."""
        return sorted(m for m in self.root.glob(f"*/*/{SEED_PREFIX}*/{EVAL}/*/{METRICS_FILE}") if m.is_file())

    def runs_evaluated(self) -> list[tuple[str, str]]:
        """(task folder, budget) of every (task, budget) here with an evaluation, in name order."""
        return sorted({(m.parents[4].name, m.parents[3].name) for m in self.evaluations()})

    @staticmethod
    def parse_task_dir(name: str) -> tuple[str, str | None]:
        """(task, link failure as written, or None) of a task folder's name <task>[-fail<p>]."""
        task, fail = _TASK_DIR.fullmatch(name or "-").groups()  # type: ignore[union-attr]
        return task, fail

    @staticmethod
    def parse_seed_dir(name: str) -> int | None:
        """The training seed k of a run directory's name seed<k>, or None for another name."""
        m = _SEED_DIR.fullmatch(name)
        return int(m.group(1)) if m else None


@dataclass(frozen=True)
class RunFolder(_Folder):
    """The artifacts of the run directory ``root`` found by its path alone, for readers without its config."""

    root: Path

    def __post_init__(self):
        object.__setattr__(self, "root", Path(self.root))


@dataclass(frozen=True)
class RunDir(_Folder):
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
        return self.trained_dir(self.model_name)

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
        return self.trained_dir(ORACLE_DIR) / MODEL

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
        return self.synthesized_as(artifact.tag, artifact.file)

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
        return self.synth_dir / TRACE

    @property
    def front_file(self) -> Path:
        """A program search's degree-budget front (synth/<tag>/front.json, synth.front=true)."""
        return self.synth_dir / FRONT

    @property
    def dataset_file(self) -> Path:
        """The oracle's dataset D, shared by every search with the same rollouts and stride."""
        return self.root / SYNTH / f"dataset-r{self.cfg.budget.synth_rollouts}-s{self.cfg.synth.stride}.pt"

    def summaries(self, stem: str) -> list[Path]:
        """summary.json of every synthesis result whose tag starts with ``stem``, sorted."""
        return sorted((self.root / SYNTH).glob(f"{stem}*/{SUMMARY}"))

    # ------------------------------------------------------------------------------------------ eval
    def eval_dir(self, label: str | None = None) -> Path:
        """eval/<label>/, the baseline's label by default."""
        return self.eval_root / (label or self.label)

    # ------------------------------------------------------------------------------------------ pictures, export
    @property
    def render_dir(self) -> Path:
        """Animations and episode pictures of the baseline (`neurosym render`)."""
        return self.render_root / self.label

    @property
    def export_dir(self) -> Path:
        """The baseline's export folder when export.dir does not name one (`neurosym export`)."""
        return self.root / EXPORT / self.label


def is_front_pick(program: str | Path) -> bool:
    """Whether a program path is one of a front's candidate files (select/front/<tag>-<name>.txt): a run's
    pipeline.select=front pick, which differs per training seed as select's pick does."""
    p = Path(program)
    return bool(str(program)) and p.parent.name == FRONT_SELECT and p.parent.parent.name == SELECT


def metrics_files(exp_dir: Path) -> list[Path]:
    """metrics.json of every baseline evaluated in the run directory ``exp_dir``, sorted."""
    return RunFolder(exp_dir).metrics_files()


def history_files(root: Path) -> list[Path]:
    """history.csv of every model trained under ``root``: a runs folder of seed directories, or one run directory."""
    return (sorted(Path(root).glob(f"seed*/{TRAIN}/*/{HISTORY}"))
            or sorted(Path(root).glob(f"{TRAIN}/*/{HISTORY}")))
