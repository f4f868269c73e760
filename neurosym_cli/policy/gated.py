"""Communication decisions as actions (paper appendix D): the policy itself decides, for every ordered pair, whether
agent i hears agent j, and learns it by policy gradient on the task cost plus a communication cost.

The gate of pair (i, j) in round r is a Bernoulli decision with logit
    u_ij = a_r l_ij + b_r + g_r(o_ij)
where l_ij is the transformer's attention logit (the key-query score of section 3.1), a_r, b_r scalars and g_r a
small network of agent i's observation o_ij of j. It is as decentralised as the transformer: agent i decides from
its own state and its own view of j. With ``a = 1, b = 0, g = 0`` at the start (the last layer of g starts at
zero), an agent hears j with probability sigmoid(l_ij), so a gate started on the pretrained oracle
(``rl.init=oracle``) asks first whom the oracle attends to.

Training (``training.fit``) keeps the gradient of the motion through the differentiable dynamics for the sampled
masks, and adds a score-function (REINFORCE) term for the discrete decisions (``score_function_loss``). The gate's
inputs l_ij and o_ij enter it with a stop-gradient, so the score-function term trains the gate alone: for the
gate's parameters it is an unbiased estimate of the gradient of the expected discounted cost; for the
transformer's, the path by which its weights move the states and logits that later decisions read is dropped, a
bias taken for variance (measured: through that path the transformer's gradient norm was ~10^4 against ~10 for
the motion's; docs/fidelity.md, 'Communication decisions as actions').
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from ..tasks.base import eye_mask
from .protocol import CommBase


class GatedComm(nn.Module, CommBase):
    """rl: a learned Bernoulli gate per ordered pair and round (see the module docstring). ``select`` samples the
    mask from the bucket's random source; while gradients are enabled it also records, per step, the summed
    log-probability of the decisions taken and the communication degree they cost (``pop_step``)."""

    name = "gated"

    def __init__(self, rounds: int, hidden: int = 16, pair_dim: int = 2):
        super().__init__()
        self.rounds, self.hidden = rounds, hidden
        self.scale = nn.Parameter(torch.ones(rounds))  # a_r
        self.bias = nn.Parameter(torch.zeros(rounds))  # b_r
        self.edge = nn.ModuleList(nn.Sequential(nn.Linear(pair_dim, hidden), nn.ReLU(), nn.Linear(hidden, 1))
                                  for _ in range(rounds))  # g_r(o_ij)
        for g in self.edge:
            nn.init.zeros_(g[-1].weight)
            nn.init.zeros_(g[-1].bias)
        self._logp: list[Tensor] = []
        self._degree: list[Tensor] = []

    def gate_logits(self, logits: Tensor, rel: Tensor, round: int) -> Tensor:
        """logits (B, N, N) attention logits, rel (B, N, N, Dp) observations o_ij -> (B, N, N) gate logits u_ij."""
        r = min(round, self.rounds - 1)
        return self.scale[r] * logits + self.bias[r] + self.edge[r](rel).squeeze(-1)

    def select(self, ctx, logits: Tensor, round: int) -> Tensor:
        u = self.gate_logits(logits.detach(), ctx.obs.rel.detach(), round)  # (B, N, N); inputs: stop-gradient
        b, n, _ = u.shape
        others = ~eye_mask(n, u.device).expand(b, n, n)
        mask = (ctx.rng.rand(b, n, n) < torch.sigmoid(u.detach())) & others  # (B, N, N) bool: i hears j
        if torch.is_grad_enabled():
            logp = torch.where(mask, F.logsigmoid(u), F.logsigmoid(-u)).masked_fill(~others, 0.0)
            self._logp.append(logp.sum((1, 2)))  # (B,) log-probability of this round's decisions
            m = mask.float()
            self._degree.append((m.sum(2) + m.sum(1)).amax(1))  # (B,) max_i in + out, the paper's deg
        return mask

    # no picks (CommBase's None): the gate needs the logits, the dense path

    def pop_step(self) -> tuple[Tensor, Tensor] | None:
        """The step just rolled out: ((B,) summed log-probability of every decision of every round, (B,) degree
        averaged over rounds), or None when nothing was recorded (no gradients); clears the record."""
        if not self._logp:
            return None
        logp, deg = torch.stack(self._logp).sum(0), torch.stack(self._degree).mean(0)
        self._logp, self._degree = [], []
        return logp, deg


def returns(cost: Tensor, degree: Tensor, discount: Tensor, weight: float, shaped: bool) -> Tensor:
    """(T, B) the return each step's decisions answer for (see ``score_function_loss``), detached."""
    c = (cost.detach() + weight * degree.detach()) * discount[:, None]  # (T, B)
    if shaped:
        return c.flip(0).cumsum(0).flip(0)  # (T, B): sum over s >= t
    return c.sum(0, keepdim=True).expand_as(c)


def score_function_loss(cost: Tensor, degree: Tensor, logp: Tensor, discount: Tensor, weight: float,
                        shaped: bool, fallback: Tensor | None = None) -> Tensor:
    """Surrogate whose gradient is the score-function estimate of the gradient of the expected cost through the
    decisions: sum_t sum_e A_te * logp_te, the advantage A detached.

    cost (T, B) task cost per step, degree (T, B) communication degree per step, logp (T, B) summed log-probability
    of the step's decisions, discount (T,). The per-step cost is c_t = cost_t + weight * degree_t, discounted.
    shaped: a decision at step t answers for the costs from t on (reward to go: decisions cannot change the past,
    so dropping earlier costs keeps the estimate unbiased and lowers its variance); else for the whole episode's
    cost (plain REINFORCE). Baseline: leave-one-out, the mean return of the bucket's other episodes at the same
    step, independent of an episode's own decisions, so the estimate stays unbiased. With one episode in the
    bucket, ``fallback`` (T,), the running mean return of earlier buckets (``training.fit`` keeps it), or none."""
    return advantage_loss(returns(cost, degree, discount, weight, shaped), logp, fallback)


def advantage_loss(ret: Tensor, logp: Tensor, fallback: Tensor | None = None) -> Tensor:
    """sum_te (ret_te - baseline_te) logp_te for returns ret (T, B), detached, and log-probabilities logp (T, B); the
    baseline as in ``score_function_loss``."""
    b = ret.shape[1]
    if b > 1:
        base = (ret.sum(1, keepdim=True) - ret) / (b - 1)
    else:
        base = torch.zeros_like(ret) if fallback is None else fallback[:, None].expand_as(ret)
    return ((ret - base) * logp).sum()
