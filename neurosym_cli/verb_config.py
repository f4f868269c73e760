"""Typed schemas of the verbs that read a finished run directory: render and figures, select, stress (stdlib
only). ``config.RunConfig`` holds one of each; the schemas of training, search and evaluation live in config.py."""

from __future__ import annotations

from dataclasses import dataclass, field

from .errors import check as _check


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

    def __post_init__(self) -> None:
        _check(self.format in ("gif", "mp4"), f"render.format must be gif or mp4, got {self.format!r}")
        _check(self.fps > 0 and self.every > 0 and self.trail >= 0 and self.round >= 1 and self.step >= 0
               and self.agent >= 0, "render.fps and render.every must be positive; render.round at least 1; "
               "render.trail, render.step and render.agent non-negative")


@dataclass
class SelectConfig:
    """`neurosym select`: the paper's model selection by validation (appendix B) over a grid of configurations."""

    lam: list[float] = field(default_factory=lambda: [0.3, 0.5, 0.7, 1.0])
    """lambda-tilde values of the grid (paper appendix B)"""
    rules: list[int] = field(default_factory=lambda: [2, 3, 4, 5])
    """K values of the grid"""
    features: list[str] = field(default_factory=lambda: ["v1", "v2"])
    """feature maps of the grid"""
    finalists: int = 3
    """at most this many programs, the validation-best and those statistically similar to it (lowest degree
    first), are retrained and validated again before the choice"""
    jobs: int = 0
    """programs searched at once, one process and one thread each; 0 = one per CPU"""

    def __post_init__(self) -> None:
        _check(bool(self.lam) and all(x >= 0 for x in self.lam), "select.lam must be a non-empty list of values >= 0")
        _check(bool(self.rules) and all(k > 0 for k in self.rules), "select.rules must be a non-empty list of K > 0")
        _check(bool(self.features) and all(f in ("v1", "v2") for f in self.features),
               "select.features must be a non-empty list of v1, v2")
        _check(self.finalists >= 1, f"select.finalists must be at least 1, got {self.finalists}")
        _check(self.jobs >= 0, f"select.jobs must be non-negative, got {self.jobs}")


@dataclass
class StressConfig:
    """`neurosym stress`: trained baselines evaluated zero-shot at other team sizes and under link failure."""

    baselines: list[str] = field(default_factory=lambda: ["tf-full", "hard-attn", "dist", "prog", "prog-retrained",
                                                          "no-comm"])
    """the baselines to stress (those not trained in the run directory are skipped, by name)"""
    agents: list[int] = field(default_factory=lambda: [5, 10, 20, 40])
    """agents per group (random-cross: 4 groups, so up to 160 agents), at no link failure"""
    failure: list[float] = field(default_factory=lambda: [0.0, 0.1, 0.3, 0.5])
    """link failure rates, at the task's own team size"""
    seeds: int = 5
    """test seeds per condition (the same seeds and episodes for every baseline)"""

    def __post_init__(self) -> None:
        _check(all(n > 1 for n in self.agents), "stress.agents must be team sizes of at least 2 per group")
        _check(all(0.0 <= f < 1.0 for f in self.failure), "stress.failure must hold rates in [0, 1)")
        _check(self.seeds > 0, f"stress.seeds must be positive, got {self.seeds}")
        _check(bool(self.agents or self.failure), "stress.agents and stress.failure are both empty")
