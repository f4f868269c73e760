"""The task boundary: what a multi-agent problem gives the rest of neurosym, and nothing more.

Shape letters used throughout the package:
    B  episodes in a batch (a *bucket*: every episode in it has the same N)
    N  agents
    G  goals (unlabeled-goals: G = N)
    T  time steps
    D  model width
    A  action size
    Ds agent observation width (``Task.obs_dim``)
    Dp pair observation width (``Task.pair_dim``)

A task is a set of pure functions of an explicit :class:`TaskState` (docs/extending.md): ``reset(batch, gen) ->
list[TaskState]`` (one bucket per distinct N, so episodes with 10 to 40 agents are batched without padding),
``observe(state, rng)``, ``step(state, action)`` and ``cost(next_state, action)``. Nothing inside a task
detaches: gradients flow from the cost back through the dynamics (paper section 3.1).
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Protocol, Sequence, TypeVar, runtime_checkable

from ..errors import ConfigError
from ..utils.lazy import LazyModule

if TYPE_CHECKING:
    import torch
    from torch import Tensor

    from .features import FeatureMap
    from .pairs import Offsets
else:
    torch = LazyModule("torch")

S = TypeVar("S", bound="TaskState")


@dataclass(frozen=True)
class TaskState:
    """State of a bucket of B episodes with N agents each. A task subclasses it and adds any tensors (goals,
    velocities, obstacles, headings); every tensor field has the episode axis first. ``None`` fields stay None.
    Slicing, moving, concatenating and detaching go through :meth:`map`, so they keep every field of a subclass."""

    pos: Tensor  # (B, N, 2) agent positions, world units: what distances, viz and the comm-range schemes read

    @property
    def batch(self) -> int:
        return self.pos.shape[0]

    @property
    def n_agents(self) -> int:
        return self.pos.shape[1]

    def map(self: S, fn: Callable[[Tensor], Tensor]) -> S:
        """The same state with ``fn`` applied to every tensor field (other fields copied)."""
        return dataclasses.replace(self, **{f.name: fn(v) for f in dataclasses.fields(self)
                                            if isinstance(v := getattr(self, f.name), torch.Tensor)})

    def detach(self: S) -> S:
        return self.map(lambda t: t.detach())

    def take(self: S, episodes: slice) -> S:
        """The bucket's episodes ``episodes`` (a slice of the batch axis)."""
        return self.map(lambda t: t[episodes])

    def to(self: S, device: torch.device) -> S:
        return self.map(lambda t: t.to(device))


def concat_states(states: Sequence[S]) -> S:
    """Stack buckets with the same N (and the same state class) along the batch axis, field by field."""
    first = states[0]
    out: dict[str, Any] = {}
    for f in dataclasses.fields(first):
        v = getattr(first, f.name)
        out[f.name] = torch.cat([getattr(s, f.name) for s in states]) if isinstance(v, torch.Tensor) else v
    return dataclasses.replace(first, **out)


def split_buckets(buckets: Sequence[S], parts: int) -> list[S]:
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


def group_by_agents(states: Sequence[S], keys: Sequence) -> list[tuple[S, list]]:
    """Bucket single-episode states by agent count; ``keys`` (one per state) follow their state."""
    by_n: dict[int, list[int]] = {}
    for i, s in enumerate(states):
        by_n.setdefault(s.n_agents, []).append(i)
    return [(concat_states([states[i] for i in idx]), [keys[i] for i in idx]) for _, idx in sorted(by_n.items())]


class Observation:
    """What the agents see at one step: ``agent`` (B, N, Ds) each agent's private input s_i, and o_ij, agent i's
    (noisy) view of agent j (paper section 2), with [..., :2] = x_j - x_i by convention (distance-based features
    and schemes read the first two columns).

    ``rel`` is given either as the dense tensor (B, N, N, Dp) or as a pair source computed where read
    (tasks/pairs.py ``Offsets``: the sparse path of large teams, kept in ``pairs``); reading ``rel`` of a pair
    source builds the dense tensor once (what a dense provider needs)."""

    __slots__ = ("agent", "pairs", "_rel")

    def __init__(self, agent: Tensor, rel: "Tensor | Offsets"):
        self.agent = agent  # (B, N, Ds)
        lazy = not isinstance(rel, torch.Tensor)
        self.pairs: Offsets | None = rel if lazy else None  # type: ignore[assignment]
        self._rel: Tensor | None = None if lazy else rel  # type: ignore[assignment]

    @property
    def rel(self) -> Tensor:
        """(B, N, N, Dp) o_ij, built from the pair source on first read when there is one."""
        if self._rel is None:
            assert self.pairs is not None
            self._rel = self.pairs.dense()
        return self._rel

    @property
    def rel_shape(self) -> tuple[int, ...]:
        """(B, N, N, Dp) without building anything."""
        return tuple(self.pairs.shape if self.pairs is not None else self.rel.shape)


@dataclass(frozen=True)
class Scene:
    """What `neurosym render` and `neurosym figures` draw besides the agents: one episode's goals and groups."""

    goal: Tensor  # (G, 2) goal positions, world units
    group: Tensor  # (N,) long: colour group of each agent
    labelled: bool = True  # each agent has its own goal (coloured like it); False: a shared goal set (grey)


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

    def keys(self, batch: int) -> Tensor:
        """(B,) int64 in [0, 2^62): one counter-based key per episode (tasks/pairs.py: the sparse path's noise)."""
        return self._draw(lambda shape, **kw: torch.randint(0, 2**62, shape, **kw), batch, ())


class EpisodeSeeder(Protocol):
    def __call__(self, index: int) -> torch.Generator: ...


@runtime_checkable
class Task(Protocol):
    """The interface every task implements (all tensors batched, see the module docstring; docs/extending.md).

    A task class also has ``Config``, its typed schema (a :class:`~neurosym_cli.config.TaskConfig` subclass), and
    is built as ``Task(cfg, horizon)``. Optional capabilities (see :data:`CAPABILITIES`) are methods a task may
    leave out; a verb that needs a missing one refuses in one line that names it."""

    obs_dim: int  # Ds
    pair_dim: int  # Dp
    action_dim: int  # A
    horizon: int  # T
    rounds: int  # communication rounds per step

    def reset(self, batch: int, gen: torch.Generator) -> list[TaskState]: ...

    def test_episodes(self, seeder: EpisodeSeeder) -> tuple[list[TaskState], list[torch.Generator]]: ...

    def observe(self, state: TaskState, rng: Rng) -> Observation: ...

    def step(self, state: TaskState, action: Tensor) -> TaskState: ...

    def cost(self, next_state: TaskState, action: Tensor) -> Tensor: ...

    def target(self, action: Tensor, agent: Tensor) -> Tensor:
        """action (..., A) -> the action as it acts (what programs imitate); ``agent`` (..., Ds) is each agent's own
        input s_i, for a target that depends on the agent (a per-agent speed limit read from s_i). A target that
        needs only the action may be written ``target(self, action)``; callers go through :func:`applied_action`."""
        ...

    def metrics(self, state: TaskState) -> dict[str, Tensor]: ...

    def features(self, version: str) -> FeatureMap: ...


Target = Callable[["Tensor", "Tensor"], "Tensor"]
"""action (..., A) the transformer's output, agent (..., Ds) each agent's own input s_i (same leading axes) ->
(..., A) the action as the task applies it (Task.target: what programs imitate and exports output)"""


@functools.cache
def target_reads_agent(cls: type) -> bool:
    """Whether ``cls.target`` is ``target(action, agent)``: True; the older ``target(action)``: False. Read once per
    class (registry.task_class reads it when a task is registered); a target taking no action is a ConfigError."""
    params = list(inspect.signature(cls.target).parameters.values())[1:]  # after self
    if any(p.kind is p.VAR_POSITIONAL for p in params):
        return True
    positional = [p for p in params if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    if not positional:
        raise ConfigError(f"{cls.__name__}.target takes no action: write target(self, action, agent) or "
                          "target(self, action) (docs/extending.md)")
    return len(positional) >= 2


def applied_action(task: Any) -> Target:
    """The task's target as ``(action, agent) -> applied action`` (:data:`Target`), whichever form it is written in:
    a target of the action alone ignores ``agent``."""
    if target_reads_agent(type(task)):
        return task.target
    target = task.target
    return lambda action, agent: target(action)


REQUIRED = ("reset", "test_episodes", "observe", "step", "cost", "target", "metrics", "features")
"""the methods of :class:`Task`: a class without one of them is refused before anything runs"""
DIMENSIONS = ("obs_dim", "pair_dim", "action_dim", "horizon", "rounds")

CAPABILITIES = {
    "distances": "distances(state) -> (B, N, N) noise-free pairwise distances, +inf on the diagonal",
    "with_team_size": "with_team_size(n) -> the same task with n agents per group",
    "scene": "scene(state) -> Scene (goals and groups of episode 0) for drawing",
}
"""optional methods: name -> what it returns (quoted in the refusal)"""


def require(task: Any, capability: str, who: str) -> Callable:
    """The task's optional method ``capability``, or a one-line ConfigError naming it and who needs it."""
    fn = getattr(task, capability, None)
    if fn is None:
        raise ConfigError(f"{who} needs the task to provide {CAPABILITIES[capability]}; "
                          f"{type(task).__name__} does not (docs/extending.md, 'Optional capabilities')")
    return fn


COST_WORDS = "summed over agents"
"""how a task's per-step loss (``cost``) combines its agents, as the figures' loss axes say it, when the task class
does not say (its ``cost_words``): every built-in task's cost is a sum (docs/extending.md, 'Sum or mean')"""


def cost_words(cfg: Any) -> str:
    """The ``cost_words`` of the task class of ``cfg`` (a task config, by its ``_target_``), e.g. "averaged over
    agents"; COST_WORDS when the class has none. Anything but one non-empty line of text is a one-line ConfigError."""
    from .registry import task_class

    cls = task_class(cfg._target_)
    words = getattr(cls, "cost_words", COST_WORDS)
    if not isinstance(words, str) or not words.strip() or "\n" in words:
        raise ConfigError(f"{cls.__name__}.cost_words must be one line of text, e.g. 'averaged over agents' "
                          f"(the figures' loss axes print it), got {words!r}")
    return words.strip()


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


def pairwise_distances(pos: Tensor) -> Tensor:
    """(B, N, N) noise-free distances between agent positions (B, N, 2), self excluded by +inf."""
    d = torch.cdist(pos, pos)
    return d.masked_fill(eye_mask(pos.shape[1], d.device), float("inf"))
