"""The feature map phi(s_i, o_ij) of the programs (paper section 3.2): a task's declared features
(dsl/vocabulary.py: names, subjects, words, units, bounds) and how each is computed from an observation.

The paper's tasks build theirs from 2-D vectors (:func:`vector_map`): every 2-D vector of the agent's state and
the observation of j, each with its norm and angle (version 1); version 2 adds the products of the first state
vector's x, y with o_ij's x, y. Agent features are (B, N, 1) and broadcast over j; features of the other agent
are (B, N, N).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable, Mapping, Sequence

from ..dsl.vocabulary import VERSIONS, Feature, FeatureSet, Source, product_features, vector_features
from ..errors import ConfigError
from ..utils.lazy import LazyModule

if TYPE_CHECKING:
    import numpy as np
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")

FeatureFn = Callable[["FeatureView"], "Tensor"]
"""(view) -> (B, N, 1) for a feature of the asking agent, (B, N, N) for one of the other agent"""


@dataclass(frozen=True)
class FeatureMap:
    """A task's feature map: the declaration (``vocab``) and one function per feature."""

    vocab: FeatureSet
    fns: Mapping[str, FeatureFn] = field(repr=False)
    version: str = "v1"

    def __post_init__(self) -> None:
        missing = [n for n in self.vocab.names if n not in self.fns]
        if missing:
            raise ConfigError(f"feature map declares {', '.join(missing)} without a function to compute it")

    @property
    def names(self) -> list[str]:
        return self.vocab.names

    def view(self, agent: Tensor, rel: Tensor, first: int = 0) -> "FeatureView":
        """The features of one bucket's observation: agent (B, N, Ds), rel (B, N, N, Dp); or of a chunk of R
        receivers first..first+R-1 (the sparse path's filter scan): agent (B, R, Ds), rel (B, R, N, Dp)."""
        return FeatureView(self, agent, rel, first)


class FeatureView:
    """A bucket's features, looked up by name and computed once each. ``rows`` receivers (agent i = first + r)
    against ``n_agents`` candidates j: rows = N and first = 0 for a whole bucket."""

    def __init__(self, fmap: FeatureMap, agent: Tensor, rel: Tensor, first: int = 0):
        self.fmap, self.version = fmap, fmap.version
        self.batch, self.rows, self.n_agents, self.first = agent.shape[0], rel.shape[1], rel.shape[2], first
        self.device = agent.device
        self.agent, self.rel = agent, rel  # (B, R, Ds), (B, R, N, Dp)
        self._cache: dict[str, Tensor] = {}
        self.names = fmap.names

    def __getitem__(self, name: str) -> Tensor:
        if name not in self._cache:
            if name not in self.fmap.fns:
                raise KeyError(f"unknown feature {name!r}; this task has: {', '.join(self.names)}")
            self._cache[name] = self._checked(name, self.fmap.fns[name](self))
        return self._cache[name]

    def _checked(self, name: str, value: object) -> Tensor:
        """A feature's value, refused (one line naming it) unless it is a floating tensor of its declared shape:
        (B, N, 1) for a feature of the asking agent, (B, N, N) for one of the other agent. Checked once per view and
        feature, where it is built: a wrong shape would otherwise fail deep in the search, or broadcast silently
        into wrong numbers in eval (an (N, N) where (B, N, 1) belongs, when B = N)."""
        agent = self.fmap.vocab.agent_level(name)
        want = (self.batch, self.rows, 1 if agent else self.n_agents)
        got = tuple(value.shape) if isinstance(value, torch.Tensor) else None
        if got != want or not value.is_floating_point():  # type: ignore[union-attr]
            what = (f"a {type(value).__name__}" if got is None else
                    f"shape {got}" + ("" if value.is_floating_point() else f" of {value.dtype}"))  # type: ignore
            raise ConfigError(f"feature {name!r} of this task's feature map gives {what}, but a feature of "
                              f"{'the asking agent' if agent else 'the other agent'} is a float tensor of shape "
                              f"{'(B, N, 1)' if agent else '(B, N, N)'} = {want}; fix the function that computes it "
                              "(docs/extending.md)")
        return value  # type: ignore[return-value]

    def stacked(self) -> tuple[list[str], list[str], "np.ndarray", "np.ndarray"]:
        """(pair feature names, agent feature names, pair values (P, B N N), agent values (A, B N)) as float32
        numpy arrays on the CPU (for compiled rule scans); the view then serves its features from these arrays."""
        b, n = self.batch, self.n_agents
        vocab = self.fmap.vocab
        pair = [nm for nm in self.names if not vocab.agent_level(nm)]  # of o_ij: (B, N, N)
        agent = [nm for nm in self.names if vocab.agent_level(nm)]
        fp = torch.stack([self[nm].expand(b, n, n).reshape(-1) for nm in pair]).float().contiguous()
        fa = (torch.stack([self[nm].reshape(-1) for nm in agent]).float().contiguous() if agent
              else torch.zeros(0, b * n))
        for k, nm in enumerate(pair):
            self._cache[nm] = fp[k].view(b, n, n)
        for k, nm in enumerate(agent):
            self._cache[nm] = fa[k].view(b, n, 1)
        return pair, agent, fp.numpy(), fa.numpy()


VectorFn = Callable[["FeatureView"], "Tensor"]
"""(view) -> (B, N, 2) one of the agent's own state vectors, or (B, N, N, 2) the observation of the other agent"""


@dataclass(frozen=True)
class Columns:
    """A 2-D vector read from an observation, as data: ``sign * view.<field>[..., start:start + 2]`` (field
    ``agent`` (B, N, Ds) or ``rel`` (B, N, N, Dp)). Features built on it can be exported as code."""

    field: str
    start: int = 0
    sign: float = 1.0

    def __call__(self, v: "FeatureView") -> Tensor:
        t = getattr(v, self.field)[..., self.start:self.start + 2]
        return t if self.sign > 0 else -t

    def source(self, part: str) -> Source:
        return Source(self.field, self.start, self.sign, part)


def column_feature(name: str, of: str, words: str, cols: Columns, part: str, unit: str = "",
                   bounds: tuple[float, float] | None = None) -> tuple[Feature, FeatureFn]:
    """One feature that is a part (x, y, d, theta) of a 2-D vector of the observation, declared with its source
    (exportable), e.g. ring's dv: column_feature("dv", "other", "its speed relative to me", Columns("rel", 2), "d")."""
    import math

    b = bounds or ((0.0, math.inf) if part == "d" else (-math.pi, math.pi) if part == "theta"
                   else (-math.inf, math.inf))
    return (Feature(name, of, words, unit, b, source=cols.source(part)),  # type: ignore[arg-type]
            _parts(cols, of == "self")[part])


def _parts(vec: VectorFn, agent_level: bool) -> dict[str, FeatureFn]:
    """x, y, norm, angle of one 2-D vector; agent features get a trailing axis of 1 (they broadcast over j)."""
    post = (lambda t: t.unsqueeze(-1)) if agent_level else (lambda t: t)
    return {
        "x": lambda v: post(vec(v)[..., 0]),
        "y": lambda v: post(vec(v)[..., 1]),
        "d": lambda v: post(vec(v).norm(dim=-1)),
        "theta": lambda v: post(torch.atan2(vec(v)[..., 1], vec(v)[..., 0])),
    }


def _with_source(fs: list[Feature], vec: VectorFn) -> list[Feature]:
    """The four features of a vector, with their source when the vector is given as Columns (exportable)."""
    if not isinstance(vec, Columns):
        return fs
    parts = ("x", "y", "d", "theta")
    return [dataclasses.replace(f, source=vec.source(p)) for f, p in zip(fs, parts)]


def vector_map(state: Sequence[tuple[str, str, VectorFn]], version: str, unit: str = "world units",
               observation: VectorFn | None = None,
               extra: Sequence[tuple[Feature, FeatureFn]] = ()) -> FeatureMap:
    """The feature map of a task whose state is 2-D vectors: ``state`` lists (prefix, owner phrase, vector fn) of
    the asking agent (e.g. ('g', 'my goal', goal vector)); the observation of the other agent is o_ij's first two
    columns (``observation`` overrides). Names: <prefix>x, <prefix>y, <prefix>d, <prefix>theta; dx, dy, d, theta;
    and in v2 <first prefix>x_dx, ..._dy, <first prefix>y_dx, ..._dy. ``extra``: more (declaration, function)
    pairs, after those."""
    if version not in VERSIONS:
        raise ConfigError(f"features must be one of {', '.join(VERSIONS)}, got {version!r}")
    obs = observation or Columns("rel", 0)  # o_ij's offset x_j - x_i: the first two columns by convention
    feats: list[Feature] = []
    fns: dict[str, FeatureFn] = {}
    first: list[Feature] = []
    for prefix, owner, vec in state:
        fs = _with_source(vector_features(prefix, "self", owner, unit), vec)
        first = first or fs
        feats += fs
        fns.update({f"{prefix}{part}": fn for part, fn in _parts(vec, True).items()})
    other = _with_source(vector_features("", "other", "", unit), obs)
    feats += other
    fns.update(dict(zip(("dx", "dy", "d", "theta"), _parts(obs, False).values())))
    if version == "v2" and first:
        prods = [dataclasses.replace(p, source=Source(product=tuple(p.name.split("_"))))
                 for p in product_features(first, other)]
        feats += prods
        for p in prods:
            a, o = p.name.split("_")
            fns[p.name] = lambda v, a=a, o=o: v[a] * v[o]
    for f, fn in extra:
        feats.append(f)
        fns[f.name] = fn
    return FeatureMap(FeatureSet(tuple(feats)), fns, version)


def custom_map(features: Sequence[tuple[Feature, FeatureFn]], version: str = "v1") -> FeatureMap:
    """A feature map from (declaration, function) pairs, for tasks whose features are not 2-D vectors."""
    return FeatureMap(FeatureSet(tuple(f for f, _ in features)), {f.name: fn for f, fn in features}, version)

