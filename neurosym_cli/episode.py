"""One evaluation episode recorded step by step, for pictures: positions, whom each agent hears (the mask, the
attention weights actually used, and for a program which rule chose each edge), the loss and collisions.

The episode is one of the evaluation protocol's (``evaluation.py``): episode ``index`` counts through the test
episodes of evaluation seed 0, then seed 1, ..., with the same generator as in `neurosym eval`, so a picture
shows exactly an episode the results table averages over, and every baseline faces the same one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from .tasks.base import Rng, Task, TaskState, pairwise_distances, require
from .policy.comm import CommContext, CommProvider
from .policy.transformer import CommTransformer
from .utils.seeding import STREAM_EVAL, generator


@dataclass
class EpisodeRecord:
    """One episode of N agents over T steps and R communication rounds (numpy arrays, world units)."""

    pos: np.ndarray  # (T + 1, N, 2) positions, before the first step and after each step
    inputs: np.ndarray  # (T, N, Ds) each agent's private input s_i at step t (read by own-state features)
    goal: np.ndarray  # (N, 2) each agent's goal (formation) or (G, 2) the goal set (unlabeled)
    group: np.ndarray  # (N,) group of each agent (zeros for unlabeled)
    mask: np.ndarray  # (T, R, N, N) bool: agent i hears agent j at step t, round r
    attn: np.ndarray  # (T, R, N, N) attention weights actually used (rows sum to 1, or 0 when i hears nobody)
    picks: np.ndarray | None  # (T, R, N, K) the agent rule k picked for i (-1: nobody); programs only
    cost: np.ndarray  # (T,) loss of each step, summed over agents
    collide: np.ndarray  # (T, N) bool: after step t, the agent is closer than the collision distance to another
    labelled: bool  # formation (each agent its own goal) or unlabeled goals

    @property
    def steps(self) -> int:
        return self.cost.shape[0]

    @property
    def n_agents(self) -> int:
        return self.pos.shape[1]

    def degrees(self) -> tuple[np.ndarray, np.ndarray]:
        """(T,) max in-degree and (T,) max out-degree over agents, mean over rounds (as the evaluation)."""
        m = self.mask  # integer counts of the bool mask: no (T, R, N, N) float copy of a large team's
        return m.sum(3).max(2).mean(1), m.sum(2).max(2).mean(1)

    def rule_of_edge(self, receivers: np.ndarray | None = None) -> np.ndarray | None:
        """(T, R, N, N) int: the first rule that picked j for i (-1: no edge); only the rows of ``receivers`` (S,)
        when given, (T, R, S, N); None when no program ran."""
        if self.picks is None:
            return None
        picks = self.picks if receivers is None else self.picks[:, :, receivers]
        t, r, n, k = picks.shape
        out = np.full((t, r, n, self.n_agents), -1, dtype=np.int64)
        for rule in range(k - 1, -1, -1):  # the first rule that picked an agent names the edge
            p = picks[..., rule]
            tt, rr, ii = np.nonzero(p >= 0)
            out[tt, rr, ii, p[tt, rr, ii]] = rule
        return out


class _Recorder:
    """A provider that passes everything through and keeps the picks it handed out (the rule of each edge)."""

    def __init__(self, inner: CommProvider):
        self.inner, self.name = inner, inner.name
        self.picked: list[torch.Tensor] = []

    def select(self, ctx: CommContext, logits: torch.Tensor, round: int) -> torch.Tensor:
        return self.inner.select(ctx, logits, round)

    def picks(self, ctx: CommContext, round: int) -> torch.Tensor | None:
        p = self.inner.picks(ctx, round)
        if p is not None:
            self.picked.append(p)
        return p


def protocol_episode(env: Task, index: int, max_seeds: int = 1000) -> tuple[TaskState, torch.Generator, int]:
    """Episode ``index`` of the evaluation protocol: (its state (B = 1), its generator, its evaluation seed)."""
    if index < 0:
        raise ValueError(f"episode must be >= 0, got {index}")
    k = index
    for seed in range(max_seeds):
        eps, gens = env.test_episodes(lambda e, s=seed: generator(s, STREAM_EVAL, e))
        if k < len(eps):
            return eps[k], gens[k], seed
        k -= len(eps)
    raise ValueError(f"episode {index} is beyond {max_seeds} evaluation seeds")


@torch.no_grad()
def record_episode(env: Task, policy: CommTransformer, comm: CommProvider, state: TaskState,
                   gen: torch.Generator, device: torch.device, horizon: int | None = None) -> EpisodeRecord:
    """Roll out one episode (B = 1) as the evaluation does, keeping every step."""
    horizon = horizon or env.horizon
    was_training = policy.training
    policy.eval()
    rec = _Recorder(comm)
    rng = Rng([gen], device)
    state = state.to(device)
    pos, inputs, masks, attns, costs, collide, picks = [state.pos[0].cpu()], [], [], [], [], [], []
    dist_c = float(getattr(getattr(env, "cfg", None), "collision_dist", 0.0))
    for t in range(horizon):
        obs = env.observe(state, rng)
        inputs.append(obs.agent[0].cpu())
        ctx = CommContext(env, state, obs, rng, t)
        rec.picked.clear()
        out = policy(obs, lambda logits, r: rec.select(ctx, logits, r), lambda r: rec.picks(ctx, r))
        state = env.step(state, out.action)
        costs.append(float(env.cost(state, out.action)[0]))
        pos.append(state.pos[0].cpu())
        masks.append(torch.stack([m[0] for m in out.masks]).cpu())
        attns.append(torch.stack([a[0] for a in out.attn]).cpu())
        if rec.picked and len(rec.picked) == len(out.masks):
            picks.append(torch.stack([p[0] for p in rec.picked]).cpu())
        d = pairwise_distances(state.pos)[0]  # (N, N), +inf on the diagonal
        collide.append((d < dist_c).any(-1).cpu())
    policy.train(was_training)
    scene = require(env, "scene", "drawing an episode")(state)
    return EpisodeRecord(
        pos=torch.stack(pos).numpy(), inputs=torch.stack(inputs).float().numpy(), goal=scene.goal.cpu().numpy(),
        group=scene.group.cpu().numpy(),
        mask=torch.stack(masks).numpy(), attn=torch.stack(attns).float().numpy(),
        picks=torch.stack(picks).numpy() if len(picks) == horizon else None,
        cost=np.asarray(costs), collide=torch.stack(collide).numpy(), labelled=scene.labelled,
    )
