"""One batched rollout of a policy under a communication provider: shared by train, retrain and eval."""

from __future__ import annotations

from dataclasses import dataclass, field

import torch
from torch import Tensor

from .tasks.base import TaskState, Task, Rng
from .policy.comm import CommProvider
from .policy.transformer import CommTransformer, Heard
from .degrees import BANDWIDTH, METRICS, bandwidth
from .step import Recorder, step


@dataclass
class Trajectory:
    """Per-step records of a bucket (T steps, B episodes)."""

    cost: Tensor  # (T, B) the task's loss of each step (Task.cost); differentiable when rolled out with grad
    max_in: Tensor  # (T, B) max over agents of the in-degree (agents heard), mean over rounds
    max_out: Tensor  # (T, B) max over agents of the out-degree (agents that hear it), mean over rounds
    max_degree: Tensor  # (T, B) max over agents of in + out (the paper's deg, section 2)
    mean_degree: Tensor  # (T, B) mean over agents of in + out
    task_metrics: dict[str, Tensor] = field(default_factory=dict)  # name -> (T, B): the task's own (Task.metrics)
    logp: Tensor | None = None  # (T, B) log-probability of the step's communication decisions (rl, with grad)
    comm_degree: Tensor | None = None  # (T, B) the degree those decisions cost (rl, with grad)
    bits: Tensor | None = None  # (T, B) bits one agent hears per step, mean over agents (degrees.BANDWIDTH)
    link_share: Tensor | None = None  # (T, B) links used / N (N - 1), mean over rounds

    def episode_metrics(self) -> dict[str, Tensor]:
        """(B,) time averages: the per-episode metrics of the evaluation protocol (docs/fidelity.md): the loss and
        degrees of every task, their bandwidth, then the task's own metrics (collisions for the paper's tasks)."""
        out = {k: getattr(self, k).detach().float().mean(0) for k in METRICS}
        out.update({k: getattr(self, k).detach().float().mean(0) for k in BANDWIDTH if getattr(self, k) is not None})
        out.update({k: v.detach().float().mean(0) for k, v in self.task_metrics.items()})
        return out




def degree_stats(masks: list) -> tuple[Tensor, Tensor, Tensor, Tensor]:
    """masks: per round (B, N, N) bool (i hears j), or a ``Heard`` (the sparse path's picks: the same counts without
    the N x N mask) -> (max_in, max_out, max_deg, mean_deg), each (B,)."""
    first = masks[0].picks if isinstance(masks[0], Heard) else masks[0]
    out = torch.zeros(4, first.shape[0], device=first.device)
    for m in masks:
        if isinstance(m, Heard):
            deg_in, deg_out = m.degrees()  # integer counts: exact, whatever the order of the sums
        else:
            m = m.float()
            deg_in, deg_out = m.sum(2), m.sum(1)  # (B, N): row sums = heard by i; column sums = hearing j
        deg = deg_in + deg_out
        out += torch.stack([deg_in.amax(1), deg_out.amax(1), deg.amax(1), deg.mean(1)])
    out /= len(masks)
    return out[0], out[1], out[2], out[3]


def rollout(
    env: Task,
    policy: CommTransformer,
    comm: CommProvider,
    state: TaskState,
    rng: Rng,
    horizon: int,
    *,
    detach_state: bool = False,
    stats: bool = True,
    record: Recorder | None = None,
) -> Trajectory:
    """Run ``horizon`` steps (``step.step``) from ``state``. Gradients flow through the dynamics unless
    torch.no_grad is active or ``detach_state`` cuts them between steps. ``stats=False`` skips the degree and task
    metric records (training needs only the cost; degrees are then zeros). ``record`` sees every ``Step`` after it
    is done (an episode's pictures, the synthesis dataset, golden vectors)."""
    costs, records, decisions = [], [], []
    extra: dict[str, list[Tensor]] = {}
    for t in range(horizon):
        if detach_state:
            state = state.detach()
        s = step(env, policy, comm, state, rng, t)
        state, out = s.state, s.out
        costs.append(s.cost)
        if record is not None:
            record(s)
        if (d := comm.pop_step()) is not None:  # providers whose decisions are actions (policy/gated.py)
            decisions.append(d)
        if stats:
            with torch.no_grad():
                records.append(torch.stack(degree_stats([h if isinstance(h, Heard) else h[1] for h in out.heard])))
                for k, v in env.metrics(state).items():
                    extra.setdefault(k, []).append(v)
    cost = torch.stack(costs)  # (T, B)
    logp, comm_degree = (torch.stack([d[0] for d in decisions]), torch.stack([d[1] for d in decisions])) \
        if decisions else (None, None)
    if not stats:
        zero = torch.zeros_like(cost.detach())
        return Trajectory(cost, zero, zero, zero, zero, {}, logp, comm_degree)
    s = torch.stack(records)  # (T, 4, B)
    bits, share = bandwidth(s[:, 3], agents=state.n_agents, rounds=len(out.heard), width=policy.message_dim)
    return Trajectory(cost, s[:, 0], s[:, 1], s[:, 2], s[:, 3], {k: torch.stack(v) for k, v in extra.items()}, logp,
                      comm_degree, bits, share)
