"""The names of the programs' features (paper section 3.2) and what each one describes, without tensors.

A feature phi(s_i, o_ij) describes either the asking agent i alone (its own state: its goal vector, its position,
its goals; the same for every candidate j) or the other agent j as i observes it (o_ij: offset, distance,
bearing; v2's products of i's first state vector with o_ij also vary with j). ``envs/features.py`` computes them
under these names; the readings of ``printer.describe`` and the search space use this split.
"""

from __future__ import annotations

import re

VERSIONS = ("v1", "v2")
OBSERVATION = ("dx", "dy", "d", "theta")
"""features of o_ij: the other agent as the asking agent sees it"""


def vector_names(prefix: str) -> list[str]:
    """The four features of one 2-D vector: x, y, norm, angle ('' is the observation o_ij)."""
    if not prefix:
        return list(OBSERVATION)
    return [f"{prefix}x", f"{prefix}y", f"{prefix}d", f"{prefix}theta"]


def state_prefixes(kind: str, n_goals: int) -> list[str]:
    """The state vectors of the asking agent: formation the goal vector g; unlabeled its position p and goals."""
    return ["g"] if kind == "formation" else ["p"] + [f"g{k}" for k in range(1, n_goals + 1)]


def feature_names(kind: str, n_goals: int, version: str) -> list[str]:
    """Every feature of a task's feature map, in the order envs/features.py stacks them."""
    prefixes = state_prefixes(kind, n_goals)
    names = [nm for p in prefixes for nm in vector_names(p)] + vector_names("")
    if version == "v2":
        f = prefixes[0]
        names += [f"{f}x_dx", f"{f}x_dy", f"{f}y_dx", f"{f}y_dy"]
    return names


def agent_level(name: str) -> bool:
    """True for a feature of the asking agent alone (the same for every candidate), False for one that varies with
    the other agent (o_ij, or a product with it)."""
    return name not in OBSERVATION and "_" not in name


_PARTS = {"x": "x-offset", "y": "y-offset", "d": "distance", "theta": "bearing"}


def words(name: str) -> str:
    """Plain words for a feature, with its subject: 'my distance to my goal', 'its distance' (the other agent)."""
    if name in OBSERVATION:
        return {"dx": "x-offset", "dy": "y-offset", "d": "distance", "theta": "bearing (rad)"}[name]
    if "_" in name:
        own, obs = name.split("_", 1)
        return f"{words(own)} x its {words(obs)}"
    m = re.fullmatch(r"(g\d*|p)(x|y|d|theta)", name)
    if not m:
        return name
    prefix, part = m.groups()
    unit = " (rad)" if part == "theta" else ""
    if prefix == "p":
        return {"x": "my x-position", "y": "my y-position", "d": "my distance from the origin",
                "theta": "my bearing from the origin"}[part] + unit
    goal = "my goal" if prefix == "g" else f"my goal {prefix[1:]} (by initial distance)"
    if part == "d":
        return f"my distance to {goal}"
    if part == "theta":
        return f"my bearing to {goal}{unit}"
    return f"my {_PARTS[part]} to {goal}"
