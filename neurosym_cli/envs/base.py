"""Functional, batched, differentiable multi-agent environments.

Shape letters used throughout the package:
    B  episodes in a batch (a *bucket*: every episode in it has the same N)
    N  agents
    G  goals (unlabeled-goals: G = N)
    T  time steps
    D  model width
    A  action size

An environment is a set of pure functions of an explicit :class:`EnvState`:
``reset(batch, rng) -> list[EnvState]`` (one bucket per distinct N, so episodes with 10 to 40 agents are
batched without padding), ``observe(state, rng)``, ``step(state, action)`` and ``cost(state, action)``.
Nothing inside an env detaches: gradients flow from the cost back through the dynamics (paper section 3.1).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Protocol, Sequence

import torch
from torch import Tensor


@dataclass(frozen=True)
class EnvState:
    """State of a bucket of B episodes with N agents each."""

    pos: Tensor  # (B, N, 2) agent positions, world units
    goal: Tensor  # (B, N, 2) formation: each agent's goal; unlabeled: (B, G, 2) the goal set
    group: Tensor  # (B, N) long: group index per agent (formation); zeros for unlabeled
    goal_order: Tensor | None = None  # (B, N, G) long: unlabeled, each agent's goals sorted by initial distance

    @property
    def batch(self) -> int:
        return self.pos.shape[0]

    @property
    def n_agents(self) -> int:
        return self.pos.shape[1]

    def detach(self) -> "EnvState":
        return replace(self, pos=self.pos.detach())

    def take(self, episodes: slice) -> "EnvState":
        """The bucket's episodes ``episodes`` (a slice of the batch axis)."""
        return EnvState(self.pos[episodes], self.goal[episodes], self.group[episodes],
                        None if self.goal_order is None else self.goal_order[episodes])

    def to(self, device: torch.device) -> "EnvState":
        return EnvState(
            self.pos.to(device), self.goal.to(device), self.group.to(device),
            None if self.goal_order is None else self.goal_order.to(device),
        )


def split_buckets(buckets: Sequence[EnvState], parts: int) -> list[EnvState]:
    """Cut the largest buckets along the batch axis until there are at least ``parts`` (or one episode each)."""
    out = list(buckets)
    while len(out) < parts:
        k = max(range(len(out)), key=lambda i: out[i].batch)
        b = out[k]
        if b.batch < 2:
            break
        h = b.batch // 2
        out[k:k + 1] = [b.take(slice(0, h)), b.take(slice(h, None))]
    return out


def concat_states(states: Sequence[EnvState]) -> EnvState:
    """Stack buckets with the same N along the batch axis."""
    order = [s.goal_order for s in states]
    return EnvState(
        torch.cat([s.pos for s in states]), torch.cat([s.goal for s in states]), torch.cat([s.group for s in states]),
        None if order[0] is None else torch.cat(order),  # type: ignore[arg-type]
    )


@dataclass(frozen=True)
class Observation:
    """What the agents see at one step."""

    agent: Tensor  # (B, N, Ds) each agent's private input s_i
    rel: Tensor  # (B, N, N, 2) o_ij = x_j - x_i + eps_ij: agent i's noisy view of agent j (paper section 2)


class Rng:
    """Random source of a bucket.

    Training draws for the whole batch from one generator (fast). Evaluation gives every episode its own
    generator, so an episode's noise and sampling do not depend on which other episodes share its bucket,
    and a seed re-seeds everything (docs/fidelity.md, 'Evaluation').
    """

    def __init__(self, gens: torch.Generator | Sequence[torch.Generator], device: torch.device | str = "cpu"):
        self.gens = gens
        self.device = torch.device(device)
        self._device_gen: torch.Generator | None = None
        if isinstance(gens, torch.Generator) and self.device.type != "cpu":
            # batch draws on an accelerator: a device generator seeded from the CPU one (no host-device copies)
            seed = int(torch.randint(0, 2**62, (1,), generator=gens))
            self._device_gen = torch.Generator(device=self.device).manual_seed(seed)

    def _draw(self, fn, batch: int, shape: tuple[int, ...]) -> Tensor:
        if self._device_gen is not None:
            return fn((batch, *shape), generator=self._device_gen, device=self.device)
        # per-episode generators live on the CPU, so an episode's draws are the same on any device
        if isinstance(self.gens, torch.Generator):
            out = fn((batch, *shape), generator=self.gens)
        else:
            assert len(self.gens) == batch, f"{len(self.gens)} generators for {batch} episodes"
            out = torch.stack([fn(shape, generator=g) for g in self.gens])
        return out.to(self.device)

    def randn(self, batch: int, *shape: int) -> Tensor:
        return self._draw(torch.randn, batch, shape)

    def rand(self, batch: int, *shape: int) -> Tensor:
        return self._draw(torch.rand, batch, shape)


class MultiAgentEnv(Protocol):
    """The interface every task implements (all tensors batched, see module docstring)."""

    obs_dim: int  # Ds
    action_dim: int  # A
    horizon: int  # T

    def reset(self, batch: int, gen: torch.Generator) -> list[EnvState]: ...

    def test_episodes(self, seeder: "EpisodeSeeder") -> tuple[list[EnvState], list[torch.Generator]]: ...

    def observe(self, state: EnvState, rng: Rng) -> Observation: ...

    def step(self, state: EnvState, action: Tensor) -> EnvState: ...

    def effective_action(self, action: Tensor) -> Tensor: ...

    def cost(self, next_state: EnvState, action: Tensor) -> Tensor: ...

    def collisions(self, state: EnvState) -> Tensor: ...

    def true_distance(self, state: EnvState) -> Tensor: ...


class EpisodeSeeder(Protocol):
    def __call__(self, index: int) -> torch.Generator: ...


def group_by_agents(states: Sequence[EnvState], keys: Sequence) -> list[tuple[EnvState, list]]:
    """Bucket single-episode states by agent count; ``keys`` (one per state) follow their state."""
    by_n: dict[int, list[int]] = {}
    for i, s in enumerate(states):
        by_n.setdefault(s.n_agents, []).append(i)
    return [(concat_states([states[i] for i in idx]), [keys[i] for i in idx]) for _, idx in sorted(by_n.items())]


def safe_norm(x: Tensor, dim: int = -1, eps: float = 1e-12) -> Tensor:
    """Euclidean norm with a finite gradient at zero (the diagonal of pairwise distances)."""
    return torch.sqrt(torch.clamp((x * x).sum(dim), min=eps))


def clip_speed(v: Tensor, v_max: float) -> Tensor:
    """Rescale velocities (..., 2) so that their norm is at most v_max, keeping the direction."""
    speed = v.norm(dim=-1, keepdim=True) + 1e-6
    return v * (torch.clamp(speed, max=v_max) / speed)


def eye_mask(n: int, device: torch.device) -> Tensor:
    """(N, N) bool: True on the diagonal."""
    return torch.eye(n, dtype=torch.bool, device=device)
