"""The features a program may read (paper section 3.2), as data: name, subject, words, unit and bounds. No tensors.

A feature phi(s_i, o_ij) describes either the asking agent i alone (``of="self"``: its own state, the same for every
candidate j) or the other agent j as i observes it (``of="other"``: offset, distance, bearing, or a product of i's
state with o_ij). A task declares its features (``Task.features(version)``, tasks/features.py computes them); the
printer's readings, the search space, simplification and the rule pictures read only this declaration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Literal

from ..errors import ConfigError

VERSIONS = ("v1", "v2")
"""feature map versions every paper task offers (v2 adds products of the agent's state with o_ij)"""


@dataclass(frozen=True)
class Source:
    """How a feature is computed, as data (what `neurosym export` turns into code): the ``part`` (x, y, d = norm,
    theta = atan2(y, x)) of the 2-D vector ``sign * <field>[..., start:start + 2]`` of an observation (field
    ``agent``: s_i, (Ds,); ``rel``: o_ij, (Dp,)), or the ``product`` of two other features."""

    field: str = ""
    start: int = 0
    sign: float = 1.0
    part: str = ""
    product: tuple[str, ...] = ()


@dataclass(frozen=True)
class Feature:
    """One named feature of a task's feature map."""

    name: str
    """as written in programs: an identifier (letters, digits, underscores)"""
    of: Literal["self", "other"]
    """self: the asking agent's own state (a test on it is a guard); other: the candidate agent as observed"""
    words: str
    """the subject in plain language, with its owner: 'my distance to my goal', 'its bearing (rad)'"""
    unit: str = ""
    """world units, rad, or '' (dimensionless)"""
    bounds: tuple[float, float] = (-math.inf, math.inf)
    """the values the feature can take: a test outside them always or never holds (simplification, pictures)"""
    distance: bool = False
    """this is the distance to the other agent: readings say 'the nearest agent', 'within r'"""
    source: Source | None = None
    """how it is computed, as data, when it is (export needs it); None: only the task's own function knows"""


@dataclass(frozen=True)
class FeatureSet:
    """A task's features in the order it computes them (the order of the compiled rule scans)."""

    features: tuple[Feature, ...]

    def __post_init__(self) -> None:
        names = [f.name for f in self.features]
        if len(set(names)) != len(names):
            raise ConfigError(f"a task declares feature names twice: {', '.join(sorted(names))}")

    @property
    def names(self) -> list[str]:
        return [f.name for f in self.features]

    def __contains__(self, name: str) -> bool:
        return any(f.name == name for f in self.features)

    def get(self, name: str) -> Feature:
        for f in self.features:
            if f.name == name:
                return f
        raise KeyError(f"unknown feature {name!r}; this task has: {', '.join(self.names)}")

    def agent_level(self, name: str) -> bool:
        """True for a feature of the asking agent alone (the same for every candidate)."""
        return self.get(name).of == "self"

    def words(self, name: str) -> str:
        return self.get(name).words

    def bounds(self, name: str) -> tuple[float, float]:
        return self.get(name).bounds

    def unknown(self, names: Iterable[str]) -> list[str]:
        """The names that are not features of this set, sorted."""
        return sorted(set(names) - set(self.names))


_PARTS = {"x": "x-offset", "y": "y-offset", "d": "distance", "theta": "bearing"}


def vector_features(prefix: str, of: Literal["self", "other"], owner: str, unit: str = "") -> list[Feature]:
    """The four features of one 2-D vector: its x, y, norm and angle, named ``<prefix>x``, ``<prefix>y``,
    ``<prefix>d``, ``<prefix>theta`` (prefix '' is the observation o_ij: dx, dy, d, theta). ``owner`` is the
    phrase the words are built on: 'my goal' -> 'my x-offset to my goal'; '' for the observation ('its x-offset')."""
    if not prefix:
        names = ("dx", "dy", "d", "theta")
        words = ("its x-offset", "its y-offset", "its distance", "its bearing (rad)")
        bounds = ((-math.inf, math.inf), (-math.inf, math.inf), (0.0, math.inf), (-math.pi, math.pi))
        return [Feature(n, of, w, "rad" if n == "theta" else unit, b, distance=n == "d")
                for n, w, b in zip(names, words, bounds)]
    out = []
    for part in ("x", "y", "d", "theta"):
        if owner == "position":  # the agent's own position, from the origin
            w = {"x": "my x-position", "y": "my y-position", "d": "my distance from the origin",
                 "theta": "my bearing from the origin (rad)"}[part]
        elif part == "d":
            w = f"my distance to {owner}"
        elif part == "theta":
            w = f"my bearing to {owner} (rad)"
        else:
            w = f"my {_PARTS[part]} to {owner}"
        b = (0.0, math.inf) if part == "d" else (-math.pi, math.pi) if part == "theta" else (-math.inf, math.inf)
        out.append(Feature(f"{prefix}{part}", of, w, "rad" if part == "theta" else unit, b))
    return out


def product_features(state: list[Feature], other: list[Feature]) -> list[Feature]:
    """v2's quadratic terms: the x and y of the agent's first state vector times the observation's dx, dy
    (named ``<a>_<o>``, e.g. gx_dx); they vary with the candidate."""
    out = []
    for a in state[:2]:
        for o in other[:2]:
            out.append(Feature(f"{a.name}_{o.name}", "other", f"{a.words} x {o.words}",
                               f"{a.unit}^2" if a.unit and a.unit == o.unit else ""))
    return out
