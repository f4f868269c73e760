"""The single training loop (paper section 3.1; retraining, section 3.5, is the same loop with another provider).

Model-based RL by backpropagation through the differentiable dynamics: each optimizer step rolls out a batch of
episodes, sums their (discounted) per-step losses, and backpropagates through the whole horizon. The budget is
counted in rollouts, like the paper's "10k rollouts". A provider with parameters of its own (rl, appendix D:
communication decisions as actions) is trained in the same loop: its discrete decisions get a score-function term
(``policy.gated.score_function_loss``, computed here as its two parts) beside the backpropagated motion loss.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable, Protocol

import torch

from .config import BudgetConfig, OptimConfig, UserError
from .tasks.base import Task, Rng, split_buckets
from .policy.comm import CommProvider, comm_module
from .policy.gated import advantage_loss, returns
from .policy.transformer import CommTransformer
from .rollout import rollout


@dataclass
class FitSpec:
    """One training run: how many rollouts, how batched, and the optimiser (defaults live in ``OptimConfig``)."""

    rollouts: int  # total training rollouts
    batch: int  # rollouts per optimizer step
    horizon: int  # T
    optim: OptimConfig = field(default_factory=OptimConfig)
    lr: float | None = None  # starting learning rate; None: optim.lr (retraining starts at optim.retrain_lr)
    detach_state: bool = False  # cut BPTT between steps (the task's choice)
    checkpoint_every: int = BudgetConfig.checkpoint_every  # optimizer steps between save() calls
    comm_cost: float = 0.0  # rl: weight of the communication degree in the policy-gradient cost (appendix D)
    shaped: bool = True  # rl: reward to go (True) or the whole episode's return for every decision
    comm_lr_scale: float = 1.0  # rl: the gate's learning rate relative to the transformer's

    @property
    def steps(self) -> int:
        return math.ceil(self.rollouts / self.batch)

    def lr_at(self, step: int) -> float:
        """Cosine decay from the starting rate to optim.lr_final (never above the start) over the budget."""
        start = self.optim.lr if self.lr is None else self.lr
        end = min(self.optim.lr_final, start)
        frac = step / max(self.steps - 1, 1)
        return end + 0.5 * (start - end) * (1 + math.cos(math.pi * frac))


@dataclass
class FitState:
    """Everything needed to resume: stored in the checkpoint (tensors and plain data only)."""

    step: int = 0
    history: list[dict[str, float]] = field(default_factory=list)
    optimizer: dict | None = None
    gen_state: torch.Tensor | None = None
    torch_rng: torch.Tensor | None = None
    mean_return: torch.Tensor | None = None  # rl: (T,) running mean return, the baseline of one-episode buckets


class Diverged(UserError):
    """The loss, a gradient norm or a weight became nan or inf at optimizer step ``step`` (1-based); the caller
    names its checkpoint and the rate to lower (training.fit saves nothing from that step on)."""

    def __init__(self, step: int, what: str):
        super().__init__(f"training diverged at step {step}: {what}")
        self.step, self.what = step, what


class ResumeMismatch(UserError):
    """A checkpoint's optimizer or generator state does not fit the model it resumes; the caller names the file."""


def _finite_weights(groups: list[dict]) -> bool:
    return all(bool(torch.isfinite(p).all()) for g in groups for p in g["params"])


def _clip(groups: list[dict], max_norm: float, step: int) -> float:
    """Clip each parameter group's gradient on its own (the gate's score-function gradient is orders of magnitude
    larger than the motion's and must not shrink it); returns the transformer's norm before clipping. A non-finite
    norm is a divergence at ``step``: clipping would scale every gradient by nan."""
    norms = [float(torch.nn.utils.clip_grad_norm_(g["params"], max_norm)) for g in groups]
    bad = [n for n in norms if not math.isfinite(n)]
    if bad:
        raise Diverged(step, f"the gradient norm is {bad[0]}")
    return norms[0]


class Reporter(Protocol):
    def update(self, step: int, total: int, metrics: dict[str, float]) -> None: ...


def fit(
    policy: CommTransformer,
    env: Task,
    comm: CommProvider,
    spec: FitSpec,
    *,
    gen: torch.Generator,
    device: torch.device,
    reporter: Reporter,
    save: Callable[[FitState], None],
    state: FitState | None = None,
) -> FitState:
    """Train ``policy`` in place under ``comm``; ``save`` is called every ``checkpoint_every`` steps and at the end."""
    state = state or FitState()
    gate = comm_module(comm)
    groups = [{"params": list(policy.parameters()), "scale": 1.0}]
    if gate is not None:
        groups.append({"params": list(gate.parameters()), "scale": spec.comm_lr_scale})
        gate.train()
    opt = torch.optim.Adam([{"params": g["params"]} for g in groups], lr=spec.lr_at(0))
    try:
        if state.optimizer is not None:
            opt.load_state_dict(state.optimizer)
            bad = [k for g in opt.param_groups for p in g["params"] for k, v in opt.state.get(p, {}).items()
                   if isinstance(v, torch.Tensor) and v.dim() and v.shape != p.shape]
            if bad:  # Adam loads moments of any shape and fails at its first step
                raise ValueError(f"the optimizer's {bad[0]} has another shape than its weight")
        if state.gen_state is not None:
            gen.set_state(state.gen_state)
        if state.torch_rng is not None:
            torch.set_rng_state(state.torch_rng)
    except (KeyError, TypeError, ValueError, RuntimeError) as e:  # a checkpoint of the right format, edited
        raise ResumeMismatch(f"its resume state does not fit this model ({str(e).splitlines()[0][:120]})") from None
    policy.train()
    discount = spec.optim.gamma ** torch.arange(spec.horizon, dtype=torch.float32, device=device)  # (T,)
    rng = Rng(gen, device)
    mean_return = state.mean_return  # rl: running mean return per step, the baseline of one-episode buckets
    while state.step < spec.steps:
        t0 = time.perf_counter()
        batch = min(spec.batch, spec.rollouts - state.step * spec.batch)
        for group, g in zip(opt.param_groups, groups):
            group["lr"] = spec.lr_at(state.step) * g["scale"]
        opt.zero_grad(set_to_none=True)
        # ROLLOUT -> LOSS -> BACKWARD, one bucket (episodes with equal N) at a time to bound memory;
        # with step_per_bucket each bucket also gets its own CLIP -> STEP (more updates for the same rollouts)
        total_cost, total_degree, n_eps, grad_norm = 0.0, 0.0, 0, 0.0
        buckets = env.reset(batch, gen)
        if spec.optim.step_per_bucket and spec.optim.min_steps_per_batch > 1:
            buckets = split_buckets(buckets, spec.optim.min_steps_per_batch)
        for bucket in buckets:
            traj = rollout(env, policy, comm, bucket.to(device), rng, spec.horizon, detach_state=spec.detach_state,
                           stats=False)
            denom = bucket.batch if spec.optim.step_per_bucket else batch
            loss = (traj.cost * discount[:, None]).sum() / (denom * spec.horizon)
            if traj.logp is not None:  # decisions as actions: + the score-function term of their cost
                ret = returns(traj.cost, traj.comm_degree, discount, spec.comm_cost, spec.shaped)  # (T, B)
                loss = loss + advantage_loss(ret, traj.logp, mean_return) / (denom * spec.horizon)
                mean_return = ret.mean(1) if mean_return is None else 0.9 * mean_return + 0.1 * ret.mean(1)
                total_degree += float(traj.comm_degree.mean(0).sum())
            if not torch.isfinite(loss):  # checked before the step: no non-finite update reaches the weights
                raise Diverged(state.step + 1, f"the loss is {float(loss.detach())}")
            loss.backward()
            total_cost += float(traj.cost.detach().mean(0).sum())
            n_eps += bucket.batch
            if spec.optim.step_per_bucket:
                grad_norm = _clip(groups, spec.optim.grad_clip, state.step + 1)
                opt.step()
                opt.zero_grad(set_to_none=True)
        if not spec.optim.step_per_bucket:  # CLIP -> STEP once for the whole batch
            grad_norm = _clip(groups, spec.optim.grad_clip, state.step + 1)
            opt.step()
        state.step += 1
        # LOG
        metrics = {"step": state.step, "rollouts": min(state.step * spec.batch, spec.rollouts),
                   "loss": total_cost / n_eps, "grad_norm": grad_norm, "lr": spec.lr_at(state.step - 1),
                   "seconds": time.perf_counter() - t0}
        if gate is not None:
            metrics["degree"] = total_degree / n_eps  # mean over episodes of the time-averaged max degree
        state.history.append(metrics)
        reporter.update(state.step, spec.steps, metrics)
        if state.step % spec.checkpoint_every == 0 or state.step == spec.steps:
            if not _finite_weights(groups):  # a finite gradient times a huge rate: never saved, never "trained"
                raise Diverged(state.step, "a weight is no longer finite")
            state.optimizer = opt.state_dict()
            state.gen_state = gen.get_state()
            state.torch_rng = torch.get_rng_state()
            state.mean_return = mean_return  # part of the next step's loss: a resume without it differs
            save(state)
    return state
