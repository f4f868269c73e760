"""Typed configuration schemas (stdlib only, no torch).

Hydra composes the YAML values in ``conf/``; ``commands/apps.py`` registers these dataclasses as the
schemas of the primary configs, so a typo or a wrongly typed override fails at compose time, and
``OmegaConf.to_object`` hands the layers below a plain typed object whose ``__post_init__`` checks ranges.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Optional

from .baselines import BaselineConfig
from .degrees import OBJECTIVES
from .errors import ConfigError, UserError, check as _check, check_finite, check_name, cut, lies_under  # noqa: F401  (UserError: re-exported for every layer)
from .utils import compiling as _compiling, cpu as _cpu, tracking as _tracking
from .verb_config import (ExportConfig, PipelineConfig, RenderConfig, ReportConfig, RLConfig, SelectConfig,
                          StressConfig, TuneConfig)

MISSING = "???"  # OmegaConf's marker for a mandatory value (kept here so this module imports nothing heavy)
SEARCHES = ("mcmc", "hybrid")
"""synth.search: the program searches of synth/search.py"""


@dataclass
class TaskConfig:
    """What every task's schema has (paper section 4). A task's schema extends this one with its own fields and
    lives beside the task's code; a task YAML names its class by import path (``_target_``, Hydra's convention):
    conf/task/*.yaml for the paper's tasks, the user's own config directory for theirs (docs/extending.md)."""

    _target_: str = MISSING
    """import path of the task class (``package.module.Class``, or ``package.module:Class``)"""
    name: str = MISSING
    """task name as used on the command line and in run directories (random-cross, random-grid, ...)"""
    agents_per_group: int = 10
    """agents in each group (formation) or agents and goals (unlabeled); what `neurosym stress` varies"""
    horizon: int = 200
    """T: steps per episode"""
    rounds: int = 1
    """communication rounds per step (unlabeled-goals: 2, paper appendix A)"""
    detach_state: bool = False
    """cut gradients through the state between steps (reference does so for unlabeled)"""
    rules: int = 2
    """the paper's K for this task (cross 5, grid 2, unlabeled 5); the default of the top-level ``rules``"""
    lam: float = 0.25
    """the default of the top-level ``lam``, the weight of the degree term in ``objective``'s units: the paper's
    tasks state the paper's lambda-tilde (cross 0.5, grid 0.5, unlabeled 0.7) with objective paper; a task that
    states neither gets the scaled objective's 0.25 (docs/fidelity.md, 'Trade-off')"""
    objective: str = "scaled"
    """the default of ``synth.objective`` for this task (degrees.OBJECTIVES): the paper's tasks say paper"""
    eval_episodes: int = 5
    """episodes per evaluation seed when the task has no fixed test settings"""
    test_settings: list[str] = field(default_factory=list)
    """fixed evaluation settings (one episode each per seed); empty = eval_episodes random episodes"""
    link_failure: float = 0.0
    """probability that a directed link fails, independently at every step and round, for every baseline in
    training and evaluation: a selected message is lost (policy/comm.LinkFailure; docs/fidelity.md, 'Link
    failure'). Above 0 the run directory is <task>-fail<p> (paper appendix E: random-grid-noisy, 0.5)"""

    def __post_init__(self) -> None:
        check_finite(self, "task.")
        if self.name != MISSING:
            check_name(self.name, "task.name")
        _check(self.horizon > 0, f"task.horizon must be positive, got {self.horizon}")
        _check(self.rounds >= 1, f"task.rounds must be at least 1, got {self.rounds}")
        _check(self.agents_per_group > 1, "task.agents_per_group must be at least 2")
        _check(self.eval_episodes > 0, "task.eval_episodes must be positive")
        _check(self.objective in OBJECTIVES, f"task.objective must be one of {', '.join(OBJECTIVES)}, "
               f"got {self.objective!r}")
        _check(0.0 <= self.link_failure < 1.0, f"task.link_failure must lie in [0, 1), got {self.link_failure}")

    @property
    def max_agents(self) -> int:
        """N of the largest episode the task makes, every group together: what the memory estimate
        (policy/footprint.py) and the K < N checks read. Here agents_per_group (one group); a schema whose
        episodes hold more agents derives it from its own fields (CrossConfig: num_groups x agents_per_group).
        ``tasks.registry.probe`` refuses a task whose episodes outgrow it."""
        return self.agents_per_group


@dataclass
class ModelConfig:
    """The transformer of paper section 3.1 (reference widths, docs/fidelity.md 'Policy')."""

    width: int = 16
    """d: embedding, query, key and message width"""
    ffn: int = 16
    """hidden width of the post-attention feed-forward block"""
    dropout: float = 0.1
    """dropout on attention weights and residual branches during training"""

    def __post_init__(self) -> None:
        check_finite(self, "model.")
        _check(self.width > 0 and self.ffn > 0, "model.width and model.ffn must be positive")
        _check(0.0 <= self.dropout < 1.0, "model.dropout must lie in [0, 1)")


@dataclass
class OptimConfig:
    """Batched BPTT optimisation (docs/fidelity.md 'Training': chosen by what trains best)."""

    lr: float = 1e-2
    """Adam learning rate at the start (cosine decay to lr_final); chosen by the sweep in docs/performance.md"""
    lr_final: float = 2e-4
    """learning rate at the end of the budget (cosine decay); equal to lr for a constant rate"""
    grad_clip: float = 1.0
    """max global gradient norm"""
    gamma: float = 1.0
    """discount of the per-step loss (reference 1.0; paper says < 1)"""
    retrain_lr: float = 1e-3
    """Adam learning rate at the start of retraining (fine-tuning a trained oracle wants a smaller step)"""
    step_per_bucket: bool = True
    """one Adam step per agent-count bucket of a batch (about 4 updates per batch on random-cross, same compute;
    tasks with one agent count per batch, grid and unlabeled, get several through min_steps_per_batch)"""
    min_steps_per_batch: int = 4
    """with step_per_bucket: split a batch's buckets in halves until it gives at least this many Adam steps.
    random-cross batches mostly hold 4 agent counts already; random-grid at 750 rollouts reached train loss 82
    with 4 steps per batch vs 221 with 1, unlabeled-goals at 1k rollouts 3.99 vs 5.14 (docs/performance.md)"""

    def __post_init__(self) -> None:
        check_finite(self, "optim.")
        _check(self.lr > 0 and self.lr_final > 0 and self.retrain_lr > 0, "optim learning rates must be positive")
        _check(self.grad_clip > 0, "optim.grad_clip must be positive")
        _check(0.0 < self.gamma <= 1.0, "optim.gamma must lie in (0, 1]")
        _check(self.min_steps_per_batch >= 1, "optim.min_steps_per_batch must be at least 1")


@dataclass
class BudgetConfig:
    """How much work each stage does. Counted in rollouts, as in the paper (section 4)."""

    name: str = MISSING
    train_rollouts: int = 10_000
    """rollouts used to train the oracle (and the dist / no-comm models)"""
    batch_rollouts: int = 50
    """rollouts per optimizer step"""
    eval_seeds: int = 20
    """evaluation (test) seeds; every seed re-seeds everything"""
    val_seeds: int = 10
    """validation seeds of `neurosym select`: episodes from their own stream (utils/seeding.STREAM_VAL), so no
    validation episode is a test episode; used only to choose a configuration, never reported as a result"""
    horizon: Optional[int] = None
    """override of the task horizon (tiny budgets only); null keeps the task's"""
    retrain_rollouts: int = 1_000
    """rollouts of retraining under the program (paper: 1k)"""
    synth_rollouts: int = 300
    """oracle rollouts in the synthesis dataset D (paper: 300)"""
    mcmc_steps: int = 10_000
    """MCMC proposals per program (paper: 10,000), restarts included"""
    checkpoint_every: int = 10
    """optimizer steps between checkpoints (an interrupted run resumes from the last one)"""
    log_every: int = 5
    """optimizer steps between plain log lines (non-terminal output)"""

    def __post_init__(self) -> None:
        if self.name != MISSING:
            check_name(self.name, "budget.name")
        _check(self.train_rollouts > 0, f"budget.train_rollouts must be positive, got {self.train_rollouts}")
        _check(self.batch_rollouts > 0, f"budget.batch_rollouts must be positive, got {self.batch_rollouts}")
        _check(self.eval_seeds > 0, f"budget.eval_seeds must be positive, got {self.eval_seeds}")
        _check(self.val_seeds > 1, f"budget.val_seeds must be at least 2 (a paired interval), got {self.val_seeds}")
        _check(self.horizon is None or self.horizon > 0, "budget.horizon must be positive or null")
        _check(self.retrain_rollouts > 0, f"budget.retrain_rollouts must be positive, got {self.retrain_rollouts}")
        _check(self.synth_rollouts > 0, f"budget.synth_rollouts must be positive, got {self.synth_rollouts}")
        _check(self.mcmc_steps > 0, f"budget.mcmc_steps must be positive, got {self.mcmc_steps}")
        _check(self.checkpoint_every > 0 and self.log_every > 0, "budget.checkpoint_every/log_every must be positive")


@dataclass
class SynthConfig:
    """MCMC program synthesis (paper section 3.4; docs/fidelity.md 'Synthesis')."""

    stride: int = 10
    """keep every stride-th time step of the dataset rollouts: consecutive states are near-duplicates, and the
    scoring cost grows with the kept states (paper-size random-cross: 300 rollouts -> 6,000 states at 10)"""
    restarts: int = 4
    """independent chains from random programs before the final phase"""
    final_fraction: float = 0.2
    """share of the steps spent in the final chain started from the best program found"""
    temperature: float = 0.1
    """Metropolis temperature relative to the current objective: accept a worse program with
    probability exp(-(new - cur) / (temperature * |cur|)) (reference: 0.1)"""
    objective: str = TaskConfig.objective
    """the synthesis objective's form, composed from the task's ``objective`` (the paper's tasks: paper; every
    other: scaled): scaled (L1 / L1(silence on D) + lam * max_i(in + out) / 2K, silence scores 1, one lam for every
    task), paper (L1 + lam * max_i(in + out), L1 in the task's action units) or hinge (L1 + lam * (relu(max in - K)
    + relu(max out - K)), the reference's). degrees.OBJECTIVES; docs/fidelity.md, 'Trade-off in the task's own
    units'"""
    random_samples: int = 1
    """samples of every random rule used to estimate the expected objective (common random numbers)"""
    max_depth: int = 2
    """filter depth: 1 = single tests, 2 = and/or of two tests"""
    simplify: bool = True
    """after the search, drop filter clauses and rules that do nothing on D when the objective stays the same
    (synth/simplify.py); false keeps the searched program as found (docs/fidelity.md, 'Simplification')"""
    own_scores: bool = True
    """argmax scores may read the asking agent's own state (as the reference's search): such a score ties every
    candidate, so the pick falls to agent index order; false keeps scores to features of the other agent
    (docs/fidelity.md, 'Synthesis', has the measurement)"""
    patience: int = 0
    """end an MCMC phase (a restart or the final chain) after this many proposals without a new best of its own
    chain; 0 runs every phase to its length (the paper's chains). The steps it saves are not spent elsewhere"""
    coarse: int = 1
    """score the restart phases on every coarse-th state of D only (the same objective on a subsample); each
    restart's best is scored on the whole of D, and the final chain always runs on the whole of D. 1 = off"""
    front: bool = True
    """also search the degree-budget front: for each budget of max in+out on D, the lowest-L1 program within it
    (synth/front.py), written to synth/<tag>/front.json; the program the single-lam search picks is unchanged.
    true by default since issue 37 (false before: the paper's method)"""
    front_budgets: list[float] = field(default_factory=list)
    """the front's budgets of max in+out; empty: 0 (silence), 1, ..., min(K + N - 1, 3K)"""
    front_steps: int = 0
    """MCMC proposals of each budget's constrained search; 0: the search's steps shared among the budgets"""
    backend: str = "auto"
    """scorer kernels: numba (compiled bookkeeping and rule scans, CPU), torch (the reference code, any device),
    auto (numba on a CPU when it is installed, else torch); the objective is the same (tests compare them)"""
    search: str = "hybrid"
    """mcmc: the paper's Metropolis chains with restarts; hybrid (the default since issue 37: a better objective
    than mcmc at equal wall time on every paper task and the ring, benchmarks/bench_search.py): restarts of hill
    climbing over every single-edit neighbour, threshold fitting on the quantile grid and kicks, never scoring a
    program twice (synth/local.py). Both score budget.mcmc_steps programs; temperature, patience and coarse apply
    to mcmc only. The paper's method: synth.search=mcmc synth.front=false pipeline.select=none"""

    def __post_init__(self) -> None:
        check_finite(self, "synth.")
        _check(self.stride > 0, "synth.stride must be positive")
        _check(self.restarts >= 0, "synth.restarts must be non-negative")
        _check(0.0 <= self.final_fraction < 1.0, "synth.final_fraction must lie in [0, 1)")
        _check(self.temperature > 0, "synth.temperature must be positive")
        _check(self.objective in OBJECTIVES, f"synth.objective must be one of {', '.join(OBJECTIVES)}, "
               f"got {self.objective!r}")
        _check(all(b >= 0 for b in self.front_budgets), "synth.front_budgets must be non-negative degrees")
        _check(self.front_steps >= 0, f"synth.front_steps must be non-negative, got {self.front_steps}")
        _check(self.random_samples > 0, "synth.random_samples must be positive")
        _check(self.max_depth in (1, 2), "synth.max_depth must be 1 or 2")
        _check(self.backend in ("auto", "numba", "torch"), "synth.backend must be auto, numba or torch")
        _check(self.patience >= 0, f"synth.patience must be non-negative, got {self.patience}")
        _check(self.coarse >= 1, f"synth.coarse must be at least 1, got {self.coarse}")
        _check(self.search in SEARCHES, f"synth.search must be one of {', '.join(SEARCHES)}, got {self.search!r}")


@dataclass
class RunConfig:
    """Fields shared by every command (conf/_common_.yaml)."""

    cmd: str = MISSING
    seed: int = 0
    """training seed: fixes numpy, torch, env sampling and dropout"""
    rules: int = 2
    """K: number of program rules, also k of hard-attn and dist (paper section 4: K = d0)"""
    lam: float = TaskConfig.lam
    """weight of the degree term in synth.objective's units, composed from the task's ``lam`` (the paper's tasks:
    their lambda-tilde, cross 0.5, grid 0.5, unlabeled 0.7; every other: the scaled objective's 0.25)"""
    features: str = "v1"
    """program feature map: v1 (vectors, norms, angles) or v2 (plus quadratic terms)"""
    program: str = ""
    """show-program, eval, export: path of a program file (empty: the one synth wrote for this config)"""
    report_dir: str = ""
    """report: a directory to aggregate (empty: <runs_root>/<task>/<budget>)"""
    device: str = "auto"
    """auto (GPU when present), cpu, cuda"""
    threads: int = 1
    """torch CPU threads; 0 keeps torch's default (the cores). 1 by default: a rollout's kernels are too small to
    split (faster than 2 threads on 2 idle cores), it does not collapse beside other busy processes, and its numbers
    do not depend on the machine's core count (benchmarks/bench_contention.py; docs/performance.md)"""
    cpu_kernels: str = "avx2"
    """which CPU kernels torch and MKL run, fixed before torch loads (utils/cpu.py): avx2 pins them to the AVX2
    code paths (ATEN_CPU_CAPABILITY=avx2, MKL_CBWR=AVX2, ONEDNN_MAX_CPU_ISA=AVX2) and gives every CPU vendor MKL's
    Intel path, so one seed and thread count give the same numbers on every x86-64 machine with AVX2, AMD or Intel,
    with and without AVX-512; avx2-vendor pins the same variables but leaves MKL its own path per vendor (AMD and
    Intel differ; the default before 2026-12-03, which made docs/results.md's paper runs on AMD); native leaves
    torch and MKL to pick this CPU's widest kernels (AVX-512 where present: numbers differ in the last digits from
    AVX2 machines, and the program searches that follow may differ more). No effect off x86 (ARM has its own kernels) nor on a GPU. Set on the
    command line or in NEUROSYM_CPU_KERNELS, never in a YAML file: it must hold before torch is imported.
    Every artifact records it and what was in effect (its ``runtime``). ATen's scalar ``default`` kernels are not
    offered: every x86-64 CPU since 2013 runs the AVX2 path, and ARM has neither these kernels nor MKL, so they
    would cost speed without making more machines agree"""
    compile: str = "auto"
    """whether the one environment step (observe, the transformer's rounds, dynamics, cost) runs compiled by
    torch.compile (utils/compiling.py): off is the eager step (every committed number, bit for bit); on compiles it
    once per bucket shape (eager's numbers up to float rounding; one line and the eager step where it cannot
    compile); fused runs a dense round's pair work in hand-fused CPU kernels (policy/edge_kernels.py; 1.8x
    training a 200-agent swarm, a few % at the paper's sizes; eager's numbers up to float rounding); auto is the eager step today (docs/performance.md, 'The
    compiled step').
    Every artifact records it in its ``runtime``; a resume under another compile mode is refused"""
    runs_root: str = "outputs"
    """the directory that holds every run (NEUROSYM_RUNS; default outputs, in the working directory)"""
    exp_dir: str = MISSING
    """stable artifact directory of this (task, budget, seed); later stages find upstream files here"""
    overwrite: bool = False
    """start over instead of resuming from an existing checkpoint"""
    progress: str = "auto"
    """auto (rich bar on a terminal, log lines otherwise), rich, plain"""
    plots: bool = True
    """eval, pipeline, report, stress: draw their PNG figures (false: tables, CSV and JSON only; quicker sweeps).
    `neurosym render` and `neurosym figures` always draw"""
    logger: str = "csv"
    """run tracking (utils/tracking.py): csv (history.csv, trace.csv: always written), tensorboard (also event files
    under <exp_dir>/tensorboard), mlflow (an MLflow run per stage: MLFLOW_TRACKING_URI's store, else SQLite under
    <runs_root>/mlflow), wandb (a W&B run per stage, offline under <runs_root>/wandb without an API key); several
    joined by + (tensorboard+mlflow); each but csv needs its extra"""
    baselines: list[str] = field(default_factory=list)
    """pipeline: the baselines to make and evaluate, in order. Composed, it defaults to every scheme of
    schemes.SCHEMES made by the pipeline by default, in the paper's order (commands/apps.py fills it in)"""
    task: Any = field(default_factory=dict)
    """the task's own schema (a TaskConfig subclass named by the task class, tasks/registry.py)"""
    model: ModelConfig = field(default_factory=ModelConfig)
    optim: OptimConfig = field(default_factory=OptimConfig)
    budget: BudgetConfig = field(default_factory=BudgetConfig)
    baseline: BaselineConfig = field(default_factory=BaselineConfig)
    synth: SynthConfig = field(default_factory=SynthConfig)
    episode: int = 0
    """render, figures: the evaluation protocol's episode (0, 1, ...: the test episodes of eval seed 0, then 1, ...)"""
    render: RenderConfig = field(default_factory=RenderConfig)
    select: SelectConfig = field(default_factory=SelectConfig)
    tune: TuneConfig = field(default_factory=TuneConfig)
    pipeline: PipelineConfig = field(default_factory=PipelineConfig)
    report: ReportConfig = field(default_factory=ReportConfig)
    stress: StressConfig = field(default_factory=StressConfig)
    rl: RLConfig = field(default_factory=RLConfig)
    export: ExportConfig = field(default_factory=ExportConfig)
    selected: bool = False
    """take rules, lam, features and the search settings from the choice `neurosym select` recorded in
    <exp_dir>/select/selected.json (pipeline: run the selection first when there is none)"""

    def __post_init__(self) -> None:
        check_finite(self)
        _check(bool(self.runs_root.strip()), "runs_root is empty; name the directory that holds the runs "
               "(runs_root=outputs, or NEUROSYM_RUNS)")
        _check(bool(self.exp_dir.strip()), "exp_dir is empty; leave it out (it is <runs_root>/<task>/<budget>/seed<S>)")
        _check(self.exp_dir == MISSING or lies_under(self.exp_dir, self.runs_root),
               f"exp_dir={self.exp_dir} lies outside runs_root={self.runs_root}; every artifact is written under "
               "runs_root: set runs_root=... instead")
        _check(-2**63 <= self.seed < 2**63, f"seed={cut(self.seed)} is beyond a 64-bit integer, what every random "
               "generator takes; use a smaller one")
        _check(self.rules > 0, f"rules must be positive, got {self.rules}")
        _check(self.lam >= 0, f"lam must be non-negative, got {self.lam}")
        _check(self.device in ("auto", "cpu", "cuda") or self.device.startswith("cuda:"),
               f"device must be auto, cpu or cuda, got {self.device!r}")
        _check(self.progress in ("auto", "rich", "plain"), "progress must be auto, rich or plain")
        _check(self.threads >= 0, "threads must be non-negative")
        _check(self.cpu_kernels in _cpu.CHOICES, _cpu.check(self.cpu_kernels) or "")
        _check(self.compile in _compiling.CHOICES, _compiling.check(self.compile) or "")
        _check(self.episode >= 0, f"episode must be >= 0, got {self.episode}")
        _check(_tracking.logger_problem(self.logger) is None, _tracking.logger_problem(self.logger) or "")
        cpus = os.cpu_count() or 1
        _check(self.threads <= cpus, f"threads={self.threads}, but this machine has {cpus} CPU(s)")
        if isinstance(self.task, TaskConfig):  # RunConfig() from Python holds a bare dict: no task composed yet
            n = self.task.max_agents
            _check(self.rules < n, f"rules={self.rules}: an agent of {self.task.name} has at most {n} - 1 "
                   f"others to hear (K is also the k of hard-attn and dist)")
        _check(self.features in ("v1", "v2"), f"features must be v1 or v2, got {self.features!r}")

    def record(self) -> dict:
        """The config as written beside every artifact (JSON-safe), derived from this typed config when written:
        there is no second copy to keep in step. Resume checks compare its typed sections (``first_difference``)."""
        import dataclasses

        return dataclasses.asdict(self)

    def first_difference(self, record: dict, sections: tuple[str, ...],
                         skip: frozenset[str] = frozenset()) -> tuple[str, Any, Any] | None:
        """The first ``(section.key, recorded, this run's)`` where a ``record()`` written earlier differs from this
        config in ``sections``, or None. Fields the record lacks (added later) compare as their defaults; fields
        the schemas no longer have, and the ``skip`` keys, are ignored."""
        import dataclasses

        for key in sections:
            old = record.get(key) if isinstance(record.get(key), dict) else {}
            section = getattr(self, key)
            for f in dataclasses.fields(section):
                if f.name in skip:
                    continue
                new = getattr(section, f.name)
                dflt = f.default if f.default is not dataclasses.MISSING else (
                    f.default_factory() if f.default_factory is not dataclasses.MISSING else None)  # type: ignore[misc]
                if old.get(f.name, dflt) != new:
                    return f"{key}.{f.name}", old.get(f.name, dflt), new
        return None

    @property
    def horizon(self) -> int:
        """Steps per episode for this run (budget override, else the task's)."""
        return self.budget.horizon or self.task.horizon
