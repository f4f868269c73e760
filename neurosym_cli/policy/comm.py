"""Communication providers: every baseline of the paper is a rule that hands the transformer a mask.

A provider answers, for each round, which agents j each agent i hears: a (B, N, N) bool mask, self excluded.
The same transformer then attends over the selected agents only (paper section 3.3). Providers that know the
selection before seeing any logit (no-comm, dist, prog) also give it as picks (B, N, K), so the transformer
computes the K selected pairs only (see policy/transformer.py). The protocol every provider follows, and the
defaults of its optional members, are in policy/protocol.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from ..dsl.ast import Program
from ..dsl.interpret import program_picks
from ..tasks.base import Observation, Rng, Task, TaskState, eye_mask, require
from ..tasks.features import FeatureMap
from ..tasks.pairs import counter_uniform
from .protocol import CommBase, CommProvider, CommWrapper, require_provider, unwrap
from .scan import scan_program

__all__ = ["CommBase", "CommContext", "CommProvider", "FullComm", "LinkFailure", "NearestComm", "NoComm",
           "ProgramComm", "TopKComm", "TreeComm", "comm_module", "unwrap", "with_link_failure"]


@dataclass
class CommContext:
    """What a provider may look at during one step of a bucket."""

    env: Task
    state: TaskState
    obs: Observation
    rng: Rng
    step: int = 0
    """the time step t of the episode (0 where there is none, e.g. a single probe); schemes that change with time
    read it (expo: ExpoComm's exponential graph cycles with t)"""


def _others(logits: Tensor) -> Tensor:
    b, n, _ = logits.shape
    return ~eye_mask(n, logits.device).expand(b, n, n)


def _topk_mask(score: Tensor, k: int) -> Tensor:
    """(B, N, N) bool: the k highest scores of each row (self must already score -inf)."""
    n = score.shape[-1]
    k = min(k, n - 1)
    mask = torch.zeros_like(score, dtype=torch.bool)
    if k <= 0:
        return mask
    return mask.scatter(-1, score.topk(k, dim=-1).indices, True)


class FullComm(CommBase):
    """tf-full: every agent hears every other agent (soft attention)."""

    name = "full"

    def select(self, ctx: CommContext, logits: Tensor, round: int) -> Tensor:
        return _others(logits)


class NoComm(CommBase):
    """no-comm: nobody hears anybody; each agent acts on its own state."""

    name = "none"

    def select(self, ctx: CommContext, logits: Tensor, round: int) -> Tensor:
        return torch.zeros_like(logits, dtype=torch.bool)

    def picks(self, ctx: CommContext, round: int) -> Tensor | None:
        b, n = ctx.obs.agent.shape[:2]
        return torch.zeros(b, n, 0, dtype=torch.long, device=ctx.obs.agent.device)


class TopKComm(CommBase):
    """hard-attn: each agent hears the k others with the largest attention logits (in-degree k, every round)."""

    name = "topk"

    def __init__(self, k: int):
        self.k = k

    def select(self, ctx: CommContext, logits: Tensor, round: int) -> Tensor:
        return _topk_mask(logits.masked_fill(~_others(logits), float("-inf")), self.k)


class NearestComm(CommBase):
    """dist: each agent hears its k nearest neighbours (noise-free distances, as the reference)."""

    name = "nearest"

    def __init__(self, k: int):
        self.k = k

    def picks(self, ctx: CommContext, round: int) -> Tensor | None:
        if ctx.obs.pairs is not None:  # a large team: a chunked scan, no (B, N, N) distances
            return ctx.obs.pairs.nearest(self.k)
        d = require(ctx.env, "distances", "dist")(ctx.state)  # (B, N, N), +inf on the diagonal
        return d.topk(max(min(self.k, d.shape[-1] - 1), 0), dim=-1, largest=False).indices


class ProgramComm(CommBase):
    """prog: a synthesized program decides whom each agent hears, one program round per communication round
    (paper sections 3.2-3.3; random rules draw from the episode's random source)."""

    name = "program"

    def __init__(self, program: Program, fmap: FeatureMap):
        self.program, self.fmap = program, fmap  # fmap: the task's feature map the program reads

    def picks(self, ctx: CommContext, round: int) -> Tensor | None:
        r = min(round, self.program.n_rounds - 1)
        if ctx.obs.pairs is not None:  # a large team: the filter scan in chunks of receivers (policy/scan.py)
            return scan_program(self.program, r, self.fmap, ctx.obs, ctx.rng)
        feats = self.fmap.view(ctx.obs.agent, ctx.obs.rel)
        return program_picks(self.program, r, feats, ctx.rng)


class TreeComm(CommBase):
    """dt: a decision tree per round decides, pair by pair, whom each agent hears (paper appendix B); no cap on
    the degrees at run time."""

    name = "tree"

    def __init__(self, trees: list, fmap: FeatureMap):
        self.trees, self.fmap = trees, fmap

    def select(self, ctx: CommContext, logits: Tensor, round: int) -> Tensor:
        feats = self.fmap.view(ctx.obs.agent, ctx.obs.rel)
        return self.trees[min(round, len(self.trees) - 1)].predict(feats) & _others(logits)


class LinkFailure(CommWrapper):
    """Any provider with unreliable links: each directed link fails independently with probability ``p`` at every
    step and round, and a selected message over a failed link is lost. The inner provider chooses without
    knowing which links failed (a program's rule does not pick again), so the masks, and the degrees counted
    from them, hold only the messages actually delivered (docs/fidelity.md, 'Link failure')."""

    def __init__(self, inner: CommProvider, p: float):
        super().__init__(inner)
        self.p = p

    def _alive(self, ctx: CommContext, shape: torch.Size) -> Tensor:
        """(B, N, N) bool: link j -> i delivers this round (drawn from the bucket's random source)."""
        b, n = shape[0], shape[1]
        return ctx.rng.rand(b, n, n) >= self.p

    def select(self, ctx: CommContext, logits: Tensor, round: int) -> Tensor:
        return self.inner.select(ctx, logits, round) & self._alive(ctx, logits.shape)

    def picks(self, ctx: CommContext, round: int) -> Tensor | None:
        pk = self.inner.picks(ctx, round)
        if pk is None or pk.shape[-1] == 0:
            return pk
        if ctx.obs.pairs is not None:  # a large team: a counter-based uniform per picked link (tasks/pairs.py)
            b, n, _ = pk.shape
            recv = torch.arange(n, device=pk.device).view(1, n, 1)
            alive = counter_uniform(ctx.rng.keys(b), (recv * n + pk.clamp(min=0)).to(torch.int32)) >= self.p
        else:
            alive = self._alive(ctx, ctx.obs.agent.shape).gather(-1, pk.clamp(min=0))  # (B, N, K)
        return pk.masked_fill(~alive, -1)


def comm_module(comm: CommProvider) -> torch.nn.Module | None:
    """The provider's trainable module (rl's gate, policy/gated.py; through a link-failure wrapper), or None for a
    fixed rule."""
    inner = unwrap(comm)
    return inner if isinstance(inner, torch.nn.Module) else None


def with_link_failure(comm: CommProvider, p: float) -> CommProvider:
    """A scheme's provider as it runs: ``comm`` unchanged at p = 0 (no extra random draws: results stay
    bit-identical), else wrapped; a provider that is not a ``CommBase`` is a one-line error here, not an
    AttributeError mid-run."""
    require_provider(comm, f"the communication provider {getattr(comm, 'name', type(comm).__name__)!r}")
    return LinkFailure(comm, p) if p > 0 else comm

