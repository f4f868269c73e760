"""Typed schemas of the verbs beyond the paper's main protocol: render and figures, select, report, stress, export,
and the rl baseline with its verb (stdlib only). ``config.RunConfig`` holds one of each; the schemas of training, search and
evaluation live in config.py."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

from .errors import check as _check, check_finite, check_name


def _word(value: object) -> str:
    """A grid value as the names of its run directories write it (``lam0.3``, ``rl-c0.1``: floats by ``:g``)."""
    return str(value).lower() if isinstance(value, bool) else f"{value:g}" if isinstance(value, float) else str(value)


def check_once_each(values: list, key: str) -> None:
    """Refuse a grid that lists a value twice (as its directories name it: 0.3 and 0.30000001 are both lam0.3):
    its two jobs would write one run directory at once, and the second stop on the first's lock."""
    words = [_word(v) for v in values]
    twice = next((w for i, w in enumerate(words) if w in words[:i]), None)
    _check(twice is None, f"{key} lists {twice} twice; list each value of the grid once "
                          f"({key}=[{','.join(dict.fromkeys(words))}])")


@dataclass
class RenderConfig:
    """`neurosym render` (an episode as an animation and a picture) and `neurosym figures` (the paper's figures)."""

    format: str = "gif"
    """gif (matplotlib and Pillow) or mp4 (needs ffmpeg on the PATH)"""
    fps: int = 20
    """frames per second of the animation"""
    every: int = 1
    """a frame every this many steps"""
    trail: int = 25
    """steps of path drawn behind each agent"""
    round: int = 1
    """the communication round whose edges the animation draws (1-based; unlabeled-goals has 2)"""
    step: int = 0
    """the step whose attention the attention maps show"""
    baselines: list[str] = field(default_factory=lambda: ["hard-attn", "prog-retrained"])
    """figures: the baselines whose attention maps are drawn side by side"""
    agent: int = 0
    """figures: the asking agent of the rule-region picture (paper Figure 4)"""
    crowd_from: int = 200
    """from this many agents on, frames are drawn as a crowd: points by group, fading trails, sampled edges"""
    receivers: int = 40
    """crowd frames: the edges of this many receivers (drawn at random once, seeded) are shown, not all"""
    window: Optional[list[float]] = None
    """[x0, x1, y0, y1], world units: frames and the episode picture show this region only (a zoom into a swarm;
    crowd frames then sample their receivers among the agents that start in it); null: the whole episode"""

    def __post_init__(self) -> None:
        check_finite(self, "render.")
        _check(self.format in ("gif", "mp4"), f"render.format must be gif or mp4, got {self.format!r}")
        _check(self.fps > 0 and self.every > 0 and self.trail >= 0 and self.round >= 1 and self.step >= 0
               and self.agent >= 0, "render.fps and render.every must be positive; render.round at least 1; "
               "render.trail, render.step and render.agent non-negative")
        _check(self.crowd_from >= 1 and self.receivers >= 0,
               "render.crowd_from must be positive and render.receivers non-negative")
        if self.window is not None:
            w = [float(v) for v in self.window]
            _check(len(w) == 4 and all(math.isfinite(v) for v in w) and w[0] < w[1] and w[2] < w[3],
                   f"render.window must be [x0, x1, y0, y1] with x0 < x1 and y0 < y1 (world units), got "
                   f"{list(self.window)}; e.g. render.window=[-20,20,-10,10], or render.window=null for the whole "
                   f"episode")
            self.window = w


@dataclass
class SelectConfig:
    """`neurosym select`: the paper's model selection by validation (appendix B) over a grid of configurations."""

    lam: list[float] = field(default_factory=list)
    """lam values of the grid, in the units of synth.objective; empty: that objective's grid (degrees.LAM_GRIDS:
    the paper's 0.3-1.0 for paper and hinge, appendix B; 0.1-0.75 for scaled)"""
    rules: list[int] = field(default_factory=lambda: [2, 3, 4, 5])
    """K values of the grid"""
    features: list[str] = field(default_factory=lambda: ["v1", "v2"])
    """feature maps of the grid"""
    finalists: int = 3
    """retrained and validated again before the choice: of the programs statistically similar to the validation-best
    (itself included), this many of lowest degree (the best only when fewer similar ones have a lower degree)"""
    jobs: int = 0
    """programs searched at once, one process and one thread each; 0 = one per CPU"""

    def __post_init__(self) -> None:
        check_finite(self, "select.")
        _check(all(x >= 0 for x in self.lam), "select.lam must be a list of values >= 0 (empty: the objective's grid)")
        _check(bool(self.rules) and all(k > 0 for k in self.rules), "select.rules must be a non-empty list of K > 0")
        _check(bool(self.features) and all(f in ("v1", "v2") for f in self.features),
               "select.features must be a non-empty list of v1, v2")
        for key in ("lam", "rules", "features"):
            check_once_each(getattr(self, key), f"select.{key}")
        _check(self.finalists >= 1, f"select.finalists must be at least 1, got {self.finalists}")
        _check(self.jobs >= 0, f"select.jobs must be non-negative, got {self.jobs}")


SAMPLERS = ("tpe", "cmaes")
"""tune.sampler: Optuna's TPE (tree-structured Parzen estimator) or CMA-ES (the cmaes package; features, a
choice, are then drawn at random)"""
PRUNERS = ("median", "none")
"""tune.pruner: median stops a trial before its retraining when its program's validation loss is worse than the
median of the finished trials' (Optuna's MedianPruner); none retrains every trial"""


def _range(values: list, key: str, low: float, example: str) -> None:
    _check(len(values) == 2 and low <= values[0] <= values[1],
           f"{key} must be a range [low, high] with {low:g} <= low <= high, got {list(values)}; e.g. {key}={example}")


@dataclass
class TuneConfig:
    """`neurosym tune`: select's choice of (lam, K, features) and the retraining's rate by an Optuna study, resumable
    from its storage and shared by every process that runs the same command."""

    trials: int = 20
    """the study's target of finished trials (complete or pruned, every process's together): a rerun runs the
    missing ones, a larger value adds more, 0 only writes the table of what the study holds"""
    sampler: str = "tpe"
    """tpe or cmaes (SAMPLERS); seeded by seed, tune.worker and the trials the study held when it started"""
    pruner: str = "median"
    """median or none (PRUNERS): a trial reports its program's validation loss (before retraining) and is pruned,
    unretrained, when it is worse than the median of the finished trials'"""
    startup: int = 5
    """trials drawn at random before the sampler models the study and before the pruner prunes"""
    storage: str = ""
    """the study's database, an SQLAlchemy URL (sqlite:///..., postgresql://...); empty: SQLite in
    <exp_dir>/select/tune/optuna.db"""
    study: str = ""
    """the study's name; empty: named by the task, budget, seed, sampler and a hash of everything that sets its
    trials (the search space and the task, budget, model, optimiser and search settings)"""
    worker: int = 0
    """which of the processes that share the study this is (a SLURM array's task id, a sweep's tune.worker=0,1):
    their samplers draw apart"""
    lam: list[float] = field(default_factory=list)
    """[low, high] of lam, in synth.objective's units; empty: from the lowest to the highest of select's grid for
    that objective (degrees.LAM_GRIDS)"""
    lam_step: float = 0.05
    """lam is drawn on this grid (programs are named by their lam, and a finer one names more of them)"""
    rules: list[int] = field(default_factory=lambda: [2, 5])
    """[low, high] of K"""
    features: list[str] = field(default_factory=lambda: ["v1", "v2"])
    """the feature maps to choose among"""
    retrain_lr: list[float] = field(default_factory=lambda: [3e-4, 3e-3])
    """[low, high] of optim.retrain_lr, drawn log-uniformly and run at two significant digits"""

    def __post_init__(self) -> None:
        check_finite(self, "tune.")
        _check(self.trials >= 0, f"tune.trials must be non-negative, got {self.trials}")
        _check(self.sampler in SAMPLERS, f"tune.sampler must be one of {', '.join(SAMPLERS)}, got {self.sampler!r}")
        _check(self.pruner in PRUNERS, f"tune.pruner must be one of {', '.join(PRUNERS)}, got {self.pruner!r}")
        _check(self.startup >= 0 and self.worker >= 0, "tune.startup and tune.worker must be non-negative")
        _check(self.lam_step > 0, f"tune.lam_step must be positive, got {self.lam_step}")
        if self.lam:
            _range(self.lam, "tune.lam", 0.0, "[0.3,1.0]")
        _range(self.rules, "tune.rules", 1, "[2,5]")
        _check(bool(self.features) and all(f in ("v1", "v2") for f in self.features),
               "tune.features must be a non-empty list of v1, v2")
        check_once_each(self.features, "tune.features")
        _check(len(self.retrain_lr) == 2 and 0 < self.retrain_lr[0] <= self.retrain_lr[1],
               f"tune.retrain_lr must be a range [low, high] of rates with 0 < low <= high, got "
               f"{list(self.retrain_lr)}; e.g. tune.retrain_lr=[3e-4,3e-3]")
        if self.study:
            check_name(self.study, "tune.study")  # a folder of select/tune/


PIPELINE_SELECT = ("none", "front")
"""pipeline.select: none runs the searched program as it is; front picks among its degree-budget front"""


@dataclass
class PipelineConfig:
    """`neurosym pipeline`: how the run's programs (prog's and det-prog's) are chosen (stages/front_select.py)."""

    select: str = "front"
    """none (the paper's method, the default before issue 37): the single-lam search's program; front (default):
    for prog and for det-prog (each where listed), search the degree-budget front (synth.front=true), retrain the
    oracle under each distinct program of it (and, at its sparse end, under the nearest agent within a radius: up
    to three more retrainings), and take the lowest max in+out whose validation loss is similar to the best (``margin``; silence only where
    no-comm is as good as tf-full on validation)"""
    margin: Optional[float] = 0.01
    """select=front: a program is similar to the validation-best when the 95 % upper end of its paired loss
    difference is at most this share of the best's mean loss (an equivalence test, scale-free: the same on every
    task); null: the paper's test (the interval contains 0), which let a noisy program 6 % worse pass at 10
    validation seeds"""
    jobs: int = 0
    """stages run at once as the stage graph allows, each in its own process with ``threads`` threads (a stage
    seeds itself: the numbers are the same at any value); 0: one per CPU core this process may use over
    ``threads`` (1 on a GPU or with threads=0); 1: one after the other in this process"""

    def __post_init__(self) -> None:
        _check(self.jobs >= 0, f"pipeline.jobs must be non-negative (0 = one per core), got {self.jobs}")
        _check(self.select in PIPELINE_SELECT, f"pipeline.select must be one of {', '.join(PIPELINE_SELECT)}, "
               f"got {self.select!r}")
        _check(self.margin is None or 0 <= self.margin < 1,
               f"pipeline.margin must be a share in [0, 1) or null, got {self.margin}")


@dataclass
class ReportConfig:
    """`neurosym report`: statistics across training seeds (neurosym_cli/seeds.py, stats.py)."""

    mix: bool = False
    """report over training seeds whose settings differ (budget, task settings, K, lambda, features, search
    settings...): false refuses in one line naming the first differing key; true reports them together and says
    what differs. What `neurosym select` picked per seed is the method's outcome and may always differ"""
    seed_files: str = ""
    """a directory of seed files (docs/results/seeds, written by benchmarks/run_seeds.py) to report instead of run
    directories: every task found there, into report_dir (default: that directory's report/)"""
    reps: int = 50000
    """bootstrap resamples of the IQM and probability-of-improvement intervals (rliable's default)"""
    bootstrap_seed: int = 0
    """seed of the bootstrap: the same seed gives the same intervals"""

    def __post_init__(self) -> None:
        check_finite(self, "report.")
        _check(self.reps >= 100, f"report.reps must be at least 100, got {self.reps}")


@dataclass
class StressConfig:
    """`neurosym stress`: trained baselines evaluated zero-shot at other team sizes and under link failure."""

    baselines: list[str] = field(default_factory=lambda: ["tf-full", "hard-attn", "dist", "prog", "prog-retrained",
                                                          "no-comm"])
    """the baselines to stress (those not trained in the run directory are skipped, by name)"""
    agents: list[int] = field(default_factory=lambda: [5, 10, 20, 40])
    """agents per group, at no link failure (the default [5, 10, 20, 40] gives random-cross, 4 groups, up to 160 agents;
    task=swarm takes thousands: a size that cannot fit is reported as where the baseline stops)"""
    failure: list[float] = field(default_factory=lambda: [0.0, 0.1, 0.3, 0.5])
    """link failure rates, at the task's own team size"""
    seeds: int = 5
    """test seeds per condition (the same seeds and episodes for every baseline)"""

    def __post_init__(self) -> None:
        check_finite(self, "stress.")
        _check(all(n > 1 for n in self.agents), "stress.agents must be team sizes of at least 2 per group")
        _check(all(0.0 <= f < 1.0 for f in self.failure), "stress.failure must hold rates in [0, 1)")
        _check(self.seeds > 0, f"stress.seeds must be positive, got {self.seeds}")
        _check(bool(self.agents or self.failure), "stress.agents and stress.failure are both empty")


POLICY_FORMATS = ("torchscript", "pt2", "onnx")
"""export.formats: the policy as TorchScript (policy.pt), a torch.export program (policy.pt2), ONNX (policy.onnx and
agent/*.onnx)"""
ONNX_EXPORTERS = ("dynamo", "legacy")
"""export.onnx: torch.onnx.export(dynamo=True) (needs onnxscript) or the legacy TorchScript-based exporter"""


@dataclass
class ExportConfig:
    """`neurosym export`: a baseline's program and policy as artifacts that run without neurosym (docs/deploy.md)."""

    check: bool = False
    """replay the folder's golden vectors through every artifact in a process that cannot import neurosym,
    instead of exporting (`neurosym export --check` is the same)"""
    episodes: int = 3
    """evaluation episodes recorded as golden vectors (the protocol's episodes 0, 1, ...; a program exported
    without a trained model: the first step of at least 8 episodes)"""
    tolerance: float = 1e-5
    """the largest absolute difference of an action component the check accepts (picks must agree exactly)"""
    dir: str = ""
    """the export folder (empty: <exp_dir>/export/<baseline label>)"""
    formats: list[str] = field(default_factory=list)
    """the policy's formats to write and check, of torchscript, pt2, onnx (empty: all). A format named here that
    cannot be written or checked (its package missing, its exporter failing) fails the command after the others are
    written; one not named is one skipped line"""
    onnx: str = "dynamo"
    """the ONNX exporter: dynamo, or legacy (TorchScript-based, deprecated upstream)"""

    def __post_init__(self) -> None:
        _check(self.episodes >= 1, f"export.episodes must be at least 1, got {self.episodes}")
        bad = [f for f in self.formats if f not in POLICY_FORMATS]
        _check(not bad, f"export.formats: unknown format {bad[0] if bad else ''!r}; choose among "
                        f"{', '.join(POLICY_FORMATS)} (e.g. export.formats=[pt2,onnx]; empty: all)")
        check_once_each(self.formats, "export.formats")
        _check(self.onnx in ONNX_EXPORTERS, f"export.onnx must be one of {', '.join(ONNX_EXPORTERS)}, got "
                                            f"{self.onnx!r}")
        check_finite(self, "export.")  # tolerance=inf would pass any action
        _check(self.tolerance > 0, f"export.tolerance must be positive, got {self.tolerance}")


@dataclass
class RLConfig:
    """The rl baseline (paper appendix D: communication decisions as actions, trained by policy gradient) and
    `neurosym rl`, which trains it over a grid of the settings the paper tuned and picks rl1 and rl2."""

    cost: float = 0.1
    """weight of the communication cost: each step costs the task loss + cost * max_i(in_i + out_i)"""
    shaped: bool = True
    """true: each decision answers for the costs from its step on (reward to go); false: for the whole episode"""
    init: str = "oracle"
    """oracle: start from the pretrained transformer (needs `neurosym train`), for budget.retrain_rollouts;
    scratch: a fresh transformer, for budget.train_rollouts (the oracle's own budget)"""
    lr_scale: float = 50.0
    """the gate's learning rate relative to the transformer's"""
    grid_cost: list[float] = field(default_factory=lambda: [0.01, 0.1, 1.0, 10.0])
    """`neurosym rl`: the cost weights tried"""
    grid_shaped: list[bool] = field(default_factory=lambda: [True, False])
    """`neurosym rl`: the reward forms tried"""
    grid_init: list[str] = field(default_factory=lambda: ["oracle"])
    """`neurosym rl`: the starting points tried (scratch trains for the oracle's whole budget)"""
    jobs: int = 0
    """`neurosym rl`: settings trained at once (one process, one thread each); 0 = one per CPU"""

    def __post_init__(self) -> None:
        check_finite(self, "rl.")
        _check(self.cost >= 0 and all(c >= 0 for c in self.grid_cost), "rl.cost and rl.grid_cost must be >= 0")
        _check(self.init in ("oracle", "scratch") and all(i in ("oracle", "scratch") for i in self.grid_init),
               "rl.init and rl.grid_init must be oracle or scratch")
        _check(self.lr_scale > 0, f"rl.lr_scale must be positive, got {self.lr_scale}")
        _check(bool(self.grid_cost and self.grid_shaped and self.grid_init),
               "rl.grid_cost, rl.grid_shaped and rl.grid_init must be non-empty")
        for key in ("grid_cost", "grid_shaped", "grid_init"):
            check_once_each(getattr(self, key), f"rl.{key}")
        _check(self.jobs >= 0, f"rl.jobs must be non-negative, got {self.jobs}")
