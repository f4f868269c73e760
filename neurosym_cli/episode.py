"""One evaluation episode recorded step by step, for pictures: positions, whom each agent hears (as a list of
edges with the attention weights actually used, and for a program the rule that chose each edge; no N x N array,
so a 10,000-agent swarm records), the loss and collisions.

The episode is one of the evaluation protocol's (``evaluation.py``): episode ``index`` counts through the test
episodes of evaluation seed 0, then seed 1, ..., with the same generator as in `neurosym eval`, so a picture
shows exactly an episode the results table averages over, and every baseline faces the same one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from .tasks.base import Rng, Task, TaskState, require
from .tasks.pairs import close_pairs
from .policy.comm import CommProvider
from .policy.transformer import CommTransformer, Heard
from .rollout import rollout
from .step import Step
from .utils.seeding import STREAM_EVAL, generator


@dataclass
class Edges:
    """Whom each agent heard over an episode, one row per edge (agent i hears agent j at step t, round r), instead
    of (T, R, N, N) masks and weights: a 1,000-agent swarm's 200 steps of 2 rounds under K = 5 rules hold at most
    2 M edges (about 26 MB) where the dense masks and weights took 2.0 GB, and 10,000 agents' dense ones would not
    fit in memory at all. The rows of one (t, r) are sorted by i, then j (the order of ``np.nonzero`` on its mask)."""

    n: int  # agents N
    rounds: int  # communication rounds R
    start: np.ndarray  # (T R + 1,) int64: the rows of step t, round r are start[t R + r] : start[t R + r + 1]
    recv: np.ndarray  # (E,) int32: the listening agent i
    sent: np.ndarray  # (E,) int32: the heard agent j
    weight: np.ndarray  # (E,) float32: the attention weight a_ij actually used
    rule: np.ndarray | None  # (E,) int16: the pick slot k that chose j for i, for a program the first rule that
    # picked j (-1: none); None when the provider chose from logits (tf-full, hard-attn)

    @property
    def steps(self) -> int:
        return (len(self.start) - 1) // self.rounds

    def rows(self, t: int, r: int) -> slice:
        """The rows of step t, round r."""
        k = t * self.rounds + r
        return slice(int(self.start[k]), int(self.start[k + 1]))

    def at(self, t: int, r: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(i, j, a_ij), each (E_tr,), of step t, round r."""
        s = self.rows(t, r)
        return self.recv[s], self.sent[s], self.weight[s]

    def count(self, t: int, r: int) -> int:
        """Edges E_tr of step t, round r."""
        s = self.rows(t, r)
        return s.stop - s.start

    def mask(self, t: int, r: int) -> np.ndarray:
        """(N, N) bool: i hears j at step t, round r (a small team's picture; N^2 bytes)."""
        out = np.zeros((self.n, self.n), dtype=bool)
        i, j, _ = self.at(t, r)
        out[i, j] = True
        return out

    def weights(self, t: int, r: int) -> np.ndarray:
        """(N, N) float32: a_ij at step t, round r, zero outside the mask (rows sum to 1, or 0 for nobody heard)."""
        out = np.zeros((self.n, self.n), dtype=np.float32)
        i, j, w = self.at(t, r)
        out[i, j] = w
        return out

    def rule_at(self, t: int, r: int) -> np.ndarray | None:
        """(E_tr,) the pick slot (a program's rule) of each edge of step t, round r, aligned with ``at``; None when
        the provider chose from logits."""
        return None if self.rule is None else self.rule[self.rows(t, r)]

    def of(self, t: int, r: int, receivers: np.ndarray) -> np.ndarray:
        """(E_s,) the row numbers of step t, round r whose listener is one of ``receivers`` (S,), in order."""
        s = self.rows(t, r)
        return s.start + np.flatnonzero(np.isin(self.recv[s], receivers))

    def degrees(self) -> tuple[np.ndarray, np.ndarray]:
        """(T,) max in-degree and (T,) max out-degree over agents, mean over rounds (as the evaluation)."""
        t_n = self.steps
        din, dout = np.zeros(t_n), np.zeros(t_n)
        for t in range(t_n):
            for r in range(self.rounds):
                i, j, _ = self.at(t, r)
                din[t] += np.bincount(i, minlength=self.n).max(initial=0)
                dout[t] += np.bincount(j, minlength=self.n).max(initial=0)
        return din / self.rounds, dout / self.rounds


def round_edges(heard: "Heard | tuple[torch.Tensor, torch.Tensor]", picks: torch.Tensor | None
                ) -> tuple[np.ndarray, ...]:
    """The edges of one round of agent batch 0, from what the policy reports it heard (``PolicyOutput.heard[r]``:
    a sparse path's ``Heard``, or the dense path's (weights, mask) (B, N, N)) and the picks (B, N, K) the
    provider handed out (None: no program) -> (i, j, a_ij, rule) (E,) each, sorted by i then j; rule is -1 without
    picks."""
    if isinstance(heard, Heard):  # nothing N x N: the valid picks are the edges, and the rule is the pick's
        valid = heard.valid[0].cpu().numpy()
        i, k = np.nonzero(valid)
        j = heard.picks[0].cpu().numpy()[i, k]
        w = heard.weights[0].detach().float().cpu().numpy()[i, k]
        order = np.lexsort((j, i))
        return i[order], j[order], w[order], k[order]
    attn, mask = heard
    i, j = np.nonzero(mask[0].cpu().numpy())
    w = attn[0].detach().float().cpu().numpy()[i, j]
    rule = np.full(len(i), -1)
    if picks is not None and len(i) and picks.shape[-1]:  # the first rule whose pick for i is j (repeats once)
        hit = picks[0].cpu().numpy()[i] == j[:, None]  # (E, K)
        rule = np.where(hit.any(1), hit.argmax(1), -1)
    return i, j, w, rule


def stack_edges(n: int, rounds: int, per_round: list[tuple[np.ndarray, ...]], programs: bool) -> Edges:
    """Edges from ``round_edges`` of every (step, round), step-major."""
    sizes = [len(e[0]) for e in per_round]
    cat = [np.concatenate([e[c] for e in per_round]) if per_round else np.zeros(0) for c in range(4)]
    return Edges(n=n, rounds=rounds, start=np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64),
                 recv=cat[0].astype(np.int32), sent=cat[1].astype(np.int32), weight=cat[2].astype(np.float32),
                 rule=cat[3].astype(np.int16) if programs else None)


@dataclass
class EpisodeRecord:
    """One episode of N agents over T steps and R communication rounds (numpy arrays, world units)."""

    pos: np.ndarray  # (T + 1, N, 2) positions, before the first step and after each step
    inputs: np.ndarray  # (T, N, Ds) each agent's private input s_i at step t (read by own-state features)
    goal: np.ndarray  # (N, 2) each agent's goal (formation) or (G, 2) the goal set (unlabeled)
    group: np.ndarray  # (N,) group of each agent (zeros for unlabeled)
    edges: Edges  # whom each agent heard at each step and round, with the weights actually used
    picks: np.ndarray | None  # (T, R, N, K) int32 the agent pick slot k (a program's rule k) chose for i (-1:
    # nobody), K the episode's widest (a provider such as comm-range pads to the degree of the moment); None when
    # the provider chose from logits
    cost: np.ndarray  # (T,) the task's loss of each step (Task.cost)
    collide: np.ndarray  # (T, N) bool: after step t, the agent is closer than the collision distance to another
    labelled: bool  # formation (each agent its own goal) or unlabeled goals

    @property
    def steps(self) -> int:
        return self.cost.shape[0]

    @property
    def n_agents(self) -> int:
        return self.pos.shape[1]

    @property
    def rounds(self) -> int:
        return self.edges.rounds

    def degrees(self) -> tuple[np.ndarray, np.ndarray]:
        """(T,) max in-degree and (T,) max out-degree over agents, mean over rounds (as the evaluation)."""
        return self.edges.degrees()


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


def _pad_picks(picks: list[list[torch.Tensor]]) -> np.ndarray:
    """Per step and round picks (N, K_tr) -> (T, R, N, K) int32, padded with -1 (nobody) to the widest K."""
    k = max(p.shape[-1] for step in picks for p in step)
    out = np.full((len(picks), len(picks[0]), picks[0][0].shape[0], k), -1, dtype=np.int32)
    for t, step in enumerate(picks):
        for r, p in enumerate(step):
            out[t, r, :, :p.shape[-1]] = p.numpy()
    return out


def _colliding(pos: torch.Tensor, dist: float) -> torch.Tensor:
    """(N,) bool: agent of batch 0 closer than ``dist`` to another, by the cell list (no N x N distances)."""
    n = pos.shape[1]
    out = torch.zeros(n, dtype=torch.bool)
    if dist > 0:
        first, second = close_pairs(pos[:1], dist)
        out[first.cpu()] = True
        out[second.cpu()] = True
    return out


class _EpisodeTape:
    """The recorder of one episode (B = 1): what ``EpisodeRecord`` keeps of each step."""

    def __init__(self, state: TaskState, collision_dist: float):
        self.dist_c = collision_dist
        self.pos, self.inputs, self.edges, self.collide = [state.pos[0].cpu()], [], [], []
        self.picks: list[list[torch.Tensor]] = []  # per step with picks in every round: per round (N, K_r)
        self.rounds = 0
        self.state = state  # the latest state (the final one once the episode is done)

    def __call__(self, s: Step) -> None:
        self.inputs.append(s.obs.agent[0].cpu())
        self.pos.append(s.state.pos[0].cpu())
        programs = bool(s.picks) and all(p is not None for p in s.picks)
        self.edges += [round_edges(h, s.picks[r] if programs else None) for r, h in enumerate(s.out.heard)]
        if programs:
            self.picks.append([p[0].to(torch.int32).cpu() for p in s.picks])  # type: ignore[union-attr]
        self.collide.append(_colliding(s.state.pos, self.dist_c))
        self.rounds, self.state = len(s.out.heard), s.state


@torch.no_grad()
def record_episode(env: Task, policy: CommTransformer, comm: CommProvider, state: TaskState,
                   gen: torch.Generator, device: torch.device, horizon: int | None = None) -> EpisodeRecord:
    """Roll out one episode (B = 1) as the evaluation does, keeping every step."""
    horizon = horizon or env.horizon
    was_training = policy.training
    policy.eval()
    state = state.to(device)
    tape = _EpisodeTape(state, float(getattr(getattr(env, "cfg", None), "collision_dist", 0.0)))
    traj = rollout(env, policy, comm, state, Rng([gen], device), horizon, stats=False, record=tape)
    policy.train(was_training)
    scene = require(env, "scene", "drawing an episode")(tape.state)
    programs = len(tape.picks) == horizon
    return EpisodeRecord(
        pos=torch.stack(tape.pos).numpy(), inputs=torch.stack(tape.inputs).float().numpy(),
        goal=scene.goal.cpu().numpy(), group=scene.group.cpu().numpy(),
        edges=stack_edges(state.n_agents, tape.rounds, tape.edges, programs=programs),
        picks=_pad_picks(tape.picks) if programs else None,
        cost=traj.cost[:, 0].double().cpu().numpy(), collide=torch.stack(tape.collide).numpy(), labelled=scene.labelled,
    )
