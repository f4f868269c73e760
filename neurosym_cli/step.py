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

from dataclasses import dataclass
from typing import Callable

from torch import Tensor

from .policy.comm import CommContext, CommProvider
from .policy.transformer import CommTransformer, PolicyOutput
from .tasks.base import Observation, Rng, Task, TaskState


@dataclass
class Step:
    """What one step of a bucket saw and did."""

    t: int  # the time step of the episode, from 0
    obs: Observation  # agent (B, N, Ds) and rel (B, N, N, Dp) or a pair source: observed before the step
    out: PolicyOutput  # action (B, N, A) as the policy gave it, and per round whom each agent heard
    picks: list[Tensor | None]  # per round r: the picks (B, N, K_r) long the provider handed out (-1 = nobody),
    # None where it chose from the logits (tf-full, hard-attn)
    state: TaskState  # after the task's dynamics applied the action
    cost: Tensor  # (B,) the task's loss of the step (summed over agents); differentiable when run with grad


Recorder = Callable[[Step], None]
"""What a caller keeps of each step (an episode's positions and edges, a dataset's states, golden vectors): called
once per step, after it, in time order."""


def step(env: Task, policy: CommTransformer, comm: CommProvider, state: TaskState, rng: Rng, t: int) -> Step:
    """One step from ``state`` (B episodes): the task's observation, the communication context, the transformer's
    rounds under the provider's masks (from the logits) or picks (before any logit), the task's dynamics and cost."""
    obs = env.observe(state, rng)
    ctx = CommContext(env, state, obs, rng, t)
    picks: list[Tensor | None] = []

    def pick(r: int) -> Tensor | None:
        p = comm.picks(ctx, r)
        picks.append(p)
        return p

    out = policy(obs, lambda logits, r: comm.select(ctx, logits, r), pick)
    nxt = env.step(state, out.action)
    return Step(t, obs, out, picks, nxt, env.cost(nxt, out.action))
