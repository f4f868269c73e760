"""The feature map phi(s_i, o_ij) of the programs (paper section 3.2), with named features in world units.

Version 1 (docs/fidelity.md): every 2-D vector of the agent's state and of its observation of j, each with its
norm and angle. Formation: goal vector g_i - x_i -> gx, gy, gd, gtheta; observation o_ij -> dx, dy, d, theta.
Unlabeled goals: position -> px, py, p, ptheta; the k-th nearest goal (initial order) -> g{k}x, g{k}y, g{k}d,
g{k}theta. Version 2 adds the quadratic terms of the first state vector with o_ij (gx_dx, gx_dy, gy_dx, gy_dy).
Angles are radians in (-pi, pi]. Agent features are (B, N, 1) and broadcast over j.
"""

from __future__ import annotations

import torch
from torch import Tensor

from ..config import ConfigError

from ..dsl.vocabulary import VERSIONS, agent_level, feature_names, state_prefixes  # noqa: F401  (re-exported)


def agent_vectors(kind: str, agent: Tensor) -> tuple[list[str], Tensor]:
    """(prefixes, (B, N, V, 2)) the 2-D vectors of each agent's state, from its policy input."""
    b, n, ds = agent.shape
    if kind == "formation":
        return state_prefixes(kind, 0), (-agent).reshape(b, n, 1, 2)  # input is x - g; the goal vector is g - x
    g = (ds - 2) // 2
    vecs = torch.cat([agent[..., :2].reshape(b, n, 1, 2), (-agent[..., 2:]).reshape(b, n, g, 2)], 2)
    return state_prefixes(kind, g), vecs


class PairFeatures:
    """A FeatureView over one bucket: looks features up by name, computing each once."""

    def __init__(self, kind: str, agent: Tensor, rel: Tensor, version: str = "v1"):
        if version not in VERSIONS:
            raise ConfigError(f"features must be one of {', '.join(VERSIONS)}, got {version!r}")
        self.kind, self.version = kind, version
        self.batch, self.n_agents = agent.shape[0], agent.shape[1]
        self.device = agent.device
        self.rel = rel  # (B, N, N, 2): o_ij
        self.prefixes, self.vecs = agent_vectors(kind, agent)
        self._cache: dict[str, Tensor] = {}
        self.names = self._names()

    def _names(self) -> list[str]:
        return feature_names(self.kind, len(self.prefixes) - 1, self.version)

    def __getitem__(self, name: str) -> Tensor:
        if name not in self._cache:
            self._cache[name] = self._compute(name)
        return self._cache[name]

    def stacked(self) -> tuple[list[str], list[str], "np.ndarray", "np.ndarray"]:
        """(pair feature names, agent feature names, pair values (P, B N N), agent values (A, B N)) as float32
        numpy arrays on the CPU (for compiled rule scans); the view then serves its features from these arrays."""
        import numpy as np

        b, n = self.batch, self.n_agents
        pair = [nm for nm in self.names if not agent_level(nm)]  # of o_ij: (B, N, N)
        agent = [nm for nm in self.names if agent_level(nm)]
        fp = torch.stack([self[nm].expand(b, n, n).reshape(-1) for nm in pair]).float().contiguous()
        fa = (torch.stack([self[nm].reshape(-1) for nm in agent]).float().contiguous() if agent
              else torch.zeros(0, b * n))
        for k, nm in enumerate(pair):
            self._cache[nm] = fp[k].view(b, n, n)
        for k, nm in enumerate(agent):
            self._cache[nm] = fa[k].view(b, n, 1)
        return pair, agent, fp.numpy(), fa.numpy()

    def _compute(self, name: str) -> Tensor:
        if name not in self.names:
            raise KeyError(f"unknown feature {name!r}; this task has: {', '.join(self.names)}")
        if name in ("dx", "dy"):
            return self.rel[..., 0 if name == "dx" else 1]
        if name == "d":
            return self.rel.norm(dim=-1)
        if name == "theta":
            return torch.atan2(self.rel[..., 1], self.rel[..., 0])
        if "_" in name:  # quadratic: <state component> * <observation component>
            a, o = name.split("_")
            return self[a] * self[o]
        for k, p in enumerate(self.prefixes):
            if name.startswith(p) and name[len(p):] in ("x", "y", "d", "theta"):
                v = self.vecs[:, :, k]  # (B, N, 2)
                part = name[len(p):]
                val = {"x": lambda: v[..., 0], "y": lambda: v[..., 1], "d": lambda: v.norm(dim=-1),
                       "theta": lambda: torch.atan2(v[..., 1], v[..., 0])}[part]()
                return val.unsqueeze(-1)  # (B, N, 1): agent i's own feature, the same for every j
        raise KeyError(name)
