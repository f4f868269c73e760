"""The communication-provider protocol: every member any layer reads, its meaning and shapes, and ``CommBase``,
which gives the optional members their defaults (stdlib at import: the schemes inherit it when registered, and
`neurosym --help` stays without torch).

A provider answers, for each round of each step, whom each agent i hears. Required: ``name`` and one of
``picks`` (the sparse path) or ``select`` (the dense path); the rest have defaults on ``CommBase``:

    name         str: the provider's name in logs and errors (a wrapper keeps its inner provider's)
    picks        (ctx, round) -> (B, N, K) long, the agents each agent hears, -1 = nobody (repeats count once), or
                 None when the choice needs the transformer's logits. Default: None
    select       (ctx, logits (B, N, N), round) -> (B, N, N) bool, i hears j, self excluded. Default: the picks
                 as a mask
    picks_first  bool: ``picks`` names the agents before any logit (the sparse path: the transformer computes
                 O(N K) pairs, the memory estimate counts no (B, N, N)). Default: whether the class writes ``picks``
    pop_step     () -> ((B,) log-probability of the step's decisions, (B,) their degree) or None: for providers
                 whose decisions are actions trained by policy gradient (policy/gated.py); the rollout calls it
                 once per step, and it clears its record. Default: None
    inner        the provider a wrapper (link failure, a recorder) passes everything to; None for one that
                 decides itself. ``unwrap`` follows it to the provider that holds the program, trees or k.

``ctx`` is a ``policy.comm.CommContext`` (task, state, observation, random source, step t).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Optional, Protocol

if TYPE_CHECKING:
    from torch import Tensor

    from .comm import CommContext


class CommProvider(Protocol):
    """What every layer may read of a communication provider (the module docstring says what each member means)."""

    name: str
    inner: Optional["CommProvider"]

    @property
    def picks_first(self) -> bool: ...

    def picks(self, ctx: "CommContext", round: int) -> "Tensor | None": ...

    def select(self, ctx: "CommContext", logits: "Tensor", round: int) -> "Tensor": ...

    def pop_step(self) -> "tuple[Tensor, Tensor] | None": ...


class CommBase:
    """The defaults of a provider's optional members (module docstring). Subclass it and write ``picks`` (sparse)
    or ``select`` (dense); set ``name``."""

    inner: Optional[CommProvider] = None

    def picks(self, ctx: "CommContext", round: int) -> "Tensor | None":
        return None

    def select(self, ctx: "CommContext", logits: "Tensor", round: int) -> "Tensor":
        from ..dsl.interpret import picks_to_mask

        pk = self.picks(ctx, round)
        if pk is None:
            raise NotImplementedError(f"{type(self).__name__} writes neither picks nor select")
        return picks_to_mask(pk, ctx.obs.agent.shape[1])

    @property
    def picks_first(self) -> bool:
        """A class that writes ``picks`` runs on the sparse path; one that writes only ``select``, on the dense."""
        return type(self).picks is not CommBase.picks

    def pop_step(self) -> "tuple[Tensor, Tensor] | None":
        return None


class CommWrapper(CommBase):
    """A provider that passes everything to ``inner`` (subclasses change what passes: link failure, recorders)."""

    def __init__(self, inner: CommProvider):
        self.inner, self.name = inner, inner.name

    def picks(self, ctx: "CommContext", round: int) -> "Tensor | None":
        return self.inner.picks(ctx, round)

    def select(self, ctx: "CommContext", logits: "Tensor", round: int) -> "Tensor":
        return self.inner.select(ctx, logits, round)

    @property
    def picks_first(self) -> bool:
        return self.inner.picks_first

    def pop_step(self) -> "tuple[Tensor, Tensor] | None":
        return self.inner.pop_step()


def unwrap(comm: CommProvider) -> CommProvider:
    """The innermost provider under any wrappers: the one that holds the program, the trees, k or the gate."""
    while comm.inner is not None:
        comm = comm.inner
    return comm


def require_provider(comm: object, who: str) -> CommProvider:
    """``comm`` if it is a ``CommBase`` (so every member has a value), else a one-line error for ``who``."""
    from ..errors import ConfigError

    if not isinstance(comm, CommBase):
        raise ConfigError(f"{who} is a {type(comm).__name__}, not a neurosym_cli.policy.CommBase: make the "
                          "scheme's provider() return a CommBase subclass (docs/extending.md, section 6)")
    return comm
