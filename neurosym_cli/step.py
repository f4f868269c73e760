"""One environment step of a bucket: the one place where observe -> context -> policy -> dynamics -> cost is written.

Rollout (train, retrain, eval, rl), episode recording (pictures), dataset collection (synthesis) and the golden
vectors of export all run this step, through ``rollout.rollout``; what each of them keeps of a step is a recorder
they pass in, which reads the returned ``Step`` after the step is done. The step itself only computes: the sole
state it touches is the random source and the provider's own (a gated provider keeps its decisions for
``pop_step``), so it can be compiled as one function.

Shape letters as in policy/transformer.py: B episodes of the bucket, N agents, Ds agent input, Dp pair input,
A action, K picks of a round, R communication rounds.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Callable

from torch import Tensor

from .policy.comm import CommContext, CommProvider, comm_module
from .policy.transformer import CommTransformer, PolicyOutput
from .tasks.base import Observation, Rng, Task, TaskState
from .utils import compiling
from .utils.console import log


@dataclass
class Step:
    """What one step of a bucket saw and did."""

    t: int  # the time step of the episode, from 0
    obs: Observation  # agent (B, N, Ds) and rel (B, N, N, Dp) or a pair source: observed before the step
    out: PolicyOutput  # action (B, N, A) as the policy gave it, and per round whom each agent heard
    picks: list[Tensor | None]  # per round r: the picks (B, N, K_r) long the provider handed out (-1 = nobody),
    # None where it chose from the logits (tf-full, hard-attn)
    state: TaskState  # after the task's dynamics applied the action
    cost: Tensor  # (B,) the task's loss of the step (Task.cost: the whole team's); differentiable when run with grad


Recorder = Callable[[Step], None]
"""What a caller keeps of each step (an episode's positions and edges, a dataset's states, golden vectors): called
once per step, after it, in time order."""


def step(env: Task, policy: CommTransformer, comm: CommProvider, state: TaskState, rng: Rng, t: int) -> Step:
    """One step from ``state`` (B episodes): the task's observation, the communication context, the transformer's
    rounds under the provider's masks (from the logits) or picks (before any logit), the task's dynamics and cost.
    Under ``compile=on`` (utils/compiling.py) the same function runs compiled (``CompiledSteps``); else eager."""
    if compiling.enabled():
        return _COMPILED.step(env, policy, comm, state, rng, t)
    return eager_step(env, policy, comm, state, rng, t)


def eager_step(env: Task, policy: CommTransformer, comm: CommProvider, state: TaskState, rng: Rng, t: int,
               context: type[CommContext] = CommContext) -> Step:
    """The step as written (what ``compile=off`` runs); ``context``: the class of the provider's context."""
    obs = env.observe(state, rng)
    ctx = context(env, state, obs, rng, t)
    picks: list[Tensor | None] = []

    def pick(r: int) -> Tensor | None:
        p = comm.picks(ctx, r)
        picks.append(p)
        return p

    out = policy(obs, lambda logits, r: comm.select(ctx, logits, r), pick)
    nxt = env.step(state, out.action)
    return Step(t, obs, out, picks, nxt, env.cost(nxt, out.action))


# ---------------------------------------------------------------------------------------------- compiled step
class _Recording:
    """A bucket's random source that draws as asked and records each draw (method, batch, shape): the plan the
    compiled step's draws are made by, outside the compiled region, in the same order from the same generator."""

    def __init__(self, rng: Rng):
        self.rng, self.plan = rng, []

    def _draw(self, method: str, batch: int, *shape: int) -> Tensor:
        self.plan.append((method, batch, shape))
        return getattr(self.rng, method)(batch, *shape)

    def randn(self, batch: int, *shape: int) -> Tensor:
        return self._draw("randn", batch, *shape)

    def rand(self, batch: int, *shape: int) -> Tensor:
        return self._draw("rand", batch, *shape)

    def keys(self, batch: int) -> Tensor:
        return self._draw("keys", batch)


class _Replay:
    """The random source inside the compiled step: hands out the draws made before it, in order."""

    def __init__(self, drawn: list[Tensor]):
        self.drawn, self.i = drawn, 0

    def _next(self, *_: object) -> Tensor:
        self.i += 1
        return self.drawn[self.i - 1]

    randn = rand = keys = _next


class _Watched(CommContext):
    """A context that notes whether the provider read the time step (the compiled step does not see it)."""

    read_step = False

    def __getattribute__(self, name: str):
        if name == "step":
            type(self).read_step = True
        return object.__getattribute__(self, name)


@dataclass
class _Shape:
    """What one bucket shape of one (task, policy, provider) compiles to."""

    plan: list  # [(method, shape without the batch axis)]: the step's random draws
    fn: Callable | None  # the compiled step, None where it runs eager (it reads the time step)
    fresh: bool = True  # not yet called: its first call compiles


class CompiledSteps:
    """The step compiled per (task, policy, provider, agents, training, grad): the first step of a shape runs eager
    and records its random draws; later steps draw the same way outside the compiled region and pass the draws in
    (torch.Generator draws break a compiled graph), so the numbers are eager's up to float rounding of the fused
    kernels; dropout keeps eager's random stream (inductor's fallback_random). The batch axis is dynamic, the
    agent count static (few values: one compile each)."""

    ATTR = "_neurosym_compiled_steps"
    """the provider's attribute holding its compiled steps: they live and die with it (a process-wide table keyed
    by id() kept every provider, policy and task alive, each compiled step closing over them: a leak under select
    with compile=on)"""

    def __init__(self) -> None:
        self.generation = 0  # reset_compiled bumps it: every provider's table is stale then
        self.fallback: dict[int, dict[tuple, _Shape]] = {}  # providers that take no attribute (__slots__)
        self.said_time_step = False  # the eager note on time-step readers, once per process

    def shapes_of(self, comm: CommProvider) -> dict[tuple, _Shape]:
        """The compiled steps of one provider, per (task, policy, agents, ...) key; ids in the key are safe: its
        compiled steps hold that task and policy, so no other object takes their id while the entry lives."""
        held = getattr(comm, self.ATTR, None)
        if held is not None and held[0] == self.generation:
            return held[1]
        table: dict[tuple, _Shape] = {}
        try:
            object.__setattr__(comm, self.ATTR, (self.generation, table))  # nn.Module and frozen dataclasses too
        except (AttributeError, TypeError):
            table = self.fallback.setdefault(id(comm), table)  # __slots__: kept for the process, as before
        return table

    def step(self, env: Task, policy: CommTransformer, comm: CommProvider, state: TaskState, rng: Rng, t: int
             ) -> Step:
        import torch

        key = (id(env), id(policy), type(state), state.n_agents, state.pos.device, policy.training,
               torch.is_grad_enabled(), state.pos.requires_grad)
        shape = self.shapes_of(comm).get(key)
        if shape is None or comm_module(comm) is not None:  # a trainable provider keeps decisions: eager
            return self._record(key, env, policy, comm, state, rng, t)
        if shape.fn is None:
            return eager_step(env, policy, comm, state, rng, t)
        drawn = [getattr(rng, m)(state.batch, *s) for m, s in shape.plan]
        for x in (*drawn, *_tensors(state)):
            if x.dim():
                torch._dynamo.maybe_mark_dynamic(x, 0)
        t0 = time.perf_counter()
        try:
            out = shape.fn(state, drawn)
        except Exception as e:  # noqa: BLE001 - any compiler failure: one line, then the eager step
            compiling.fall_back(f"the step did not compile ({type(e).__name__}: {str(e).splitlines()[0][:160]})"
                                if str(e) else f"the step did not compile ({type(e).__name__})")
            return eager_step(env, policy, comm, state, _Replay(drawn), t)  # the same draws: eager's numbers
        if shape.fresh:
            shape.fresh = False
            compiling.compiled(time.perf_counter() - t0)
            log.info("compiled the step for %d agents in %.1f s", state.n_agents, time.perf_counter() - t0)
        return dataclasses.replace(out, t=t)

    def _record(self, key: tuple, env: Task, policy: CommTransformer, comm: CommProvider, state: TaskState,
                rng: Rng, t: int) -> Step:
        """The first step of a shape, eager (its numbers are the eager step's): its draws become the plan."""
        rec = _Recording(rng)
        _Watched.read_step = False
        out = eager_step(env, policy, comm, state, rec, t, context=_Watched)  # type: ignore[arg-type]
        if comm_module(comm) is not None:
            return out
        if _Watched.read_step:
            fn = None
            if not self.said_time_step:  # once per process, not per bucket shape
                self.said_time_step = True
                log.info("compile=on: the provider %s reads the time step; its steps run eager",
                         getattr(comm, "name", type(comm).__name__))
        else:
            fn = _compile(env, policy, comm)
        self.shapes_of(comm)[key] = _Shape([(m, s) for m, _, s in rec.plan], fn)
        return out


def _tensors(state: TaskState) -> list[Tensor]:
    import torch

    return [v for f in dataclasses.fields(state) if isinstance(v := getattr(state, f.name), torch.Tensor)]


def _compile(env: Task, policy: CommTransformer, comm: CommProvider) -> Callable:
    """The step of (env, policy, comm) as one compiled function of (state, draws) -> Step (t = 0: the provider
    was seen not to read it)."""
    import torch
    import torch._inductor.config as inductor

    inductor.fallback_random = True  # dropout draws from torch's own generator, as eager does
    torch._dynamo.config.recompile_limit = max(torch._dynamo.config.recompile_limit, 64)

    def core(state: TaskState, drawn: list[Tensor]) -> Step:
        return eager_step(env, policy, comm, state, _Replay(drawn), 0)  # type: ignore[arg-type]

    return torch.compile(core, **OPTIONS)


OPTIONS: dict = {"dynamic": False}
"""torch.compile's options for the step (the batch axis is marked dynamic where it is called; benchmarks try
others, e.g. mode="reduce-overhead" for CUDA graphs)"""

_COMPILED = CompiledSteps()
"""the process's compiled steps (compile=on): one entry per bucket shape seen"""


def reset_compiled() -> None:
    """Forget every compiled step (tests; a new policy object gets its own entries anyway)."""
    _COMPILED.generation += 1
    _COMPILED.fallback.clear()
    _COMPILED.said_time_step = False
