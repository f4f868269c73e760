"""Golden vectors: what every exported artifact must reproduce, recorded from evaluation episodes.

Episode k is the evaluation protocol's (episode.protocol_episode: the test episodes of eval seed 0, then 1, ...),
rolled out by the same ``rollout`` as `neurosym eval`, so its loss is the one the evaluation averages. Per step t
and round r it keeps the observation each agent had, the uniforms each random rule drew, the picks, and the action
the task applied. golden.npz holds arrays (numpy, no pickles), golden.json says what they are.

    e<k>_agent    (T, N, Ds) float32   s_i at step t
    e<k>_rel      (T, N, N, Dp) float32 o_ij at step t (agent i's view of agent j)
    e<k>_picks    (T, R, N, K) int64   whom agent i asked in round r, one slot per rule (-1: nobody); for a
                                       baseline without a program, the agents it heard, in index order, padded
    e<k>_uniform  (T, R, U, N, N) float32 the u-th random rule of round r drew [i, j] for agent i, candidate j
    e<k>_action   (T, N, A) float32    the action as applied (Task.target)
    e<k>_cost     (T,) float64         the task's loss of step t (Task.cost); the episode loss is the mean
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import torch

from ..dsl.ast import Program, RandomRule
from ..episode import protocol_episode
from ..policy.comm import CommContext, CommProvider
from ..policy.protocol import CommWrapper
from ..policy.transformer import CommTransformer
from ..rollout import rollout
from ..step import Step
from ..tasks.base import Rng, Target, Task, applied_action

FORMAT = "neurosym-golden/1"


class _TapRng:
    """The episode's random source, passed through, keeping what the program's random rules drew."""

    def __init__(self, inner: Rng, draws: list):
        self.inner, self.draws = inner, draws

    def rand(self, batch: int, *shape: int) -> torch.Tensor:
        out = self.inner.rand(batch, *shape)
        self.draws.append(out[0].cpu())
        return out

    def randn(self, batch: int, *shape: int) -> torch.Tensor:
        return self.inner.randn(batch, *shape)


class _TapComm(CommWrapper):
    """A provider passed through, keeping per round the picks it gave and its random rules' draws."""

    def __init__(self, inner: CommProvider):
        super().__init__(inner)
        self.rounds: list[tuple[torch.Tensor | None, list]] = []  # this step's (picks (N, K), draws)

    def picks(self, ctx: CommContext, round: int) -> torch.Tensor | None:
        draws: list = []
        # the same context with the random source tapped (its step too: expo's graph cycles with it)
        p = self.inner.picks(dataclasses.replace(ctx, rng=_TapRng(ctx.rng, draws)), round)  # type: ignore[arg-type]
        self.rounds.append((None if p is None else p[0].cpu(), draws))
        return p


@dataclass
class _TapSteps:
    """The recorder of a golden episode: each step's observation, masks and applied action (batch 0)."""

    target: Target  # (action, agent) -> the action as applied (tasks.base.applied_action)
    steps: list = field(default_factory=list)

    def __call__(self, s: Step) -> None:
        act = self.target(s.out.action, s.obs.agent)
        self.steps.append((s.obs.agent[0].cpu(), s.obs.rel[0].cpu(), [m[0].cpu() for m in s.out.masks], act[0].cpu()))


def _mask_picks(masks: np.ndarray) -> np.ndarray:
    """(T, R, N, N) bool -> (T, R, N, K) the agents heard in index order, padded with -1 (K >= 1)."""
    k = max(1, int(masks.sum(-1).max()))
    order = np.argsort(~masks, axis=-1, kind="stable")[..., :k]  # heard agents first, each in index order
    return np.where(np.take_along_axis(masks, order, -1), order, -1)


@torch.no_grad()
def record(task: Task, policy: CommTransformer, comm: CommProvider, program: Program | None, episodes: int,
           device: torch.device) -> tuple[dict, dict[str, np.ndarray]]:
    """(golden.json's content, golden.npz's arrays) of protocol episodes 0 .. episodes-1 under ``comm``."""
    policy.eval()
    arrays: dict[str, np.ndarray] = {}
    meta = []
    rounds = policy.n_rounds
    for k in range(episodes):
        state, gen, seed = protocol_episode(task, k)
        tap_c, tap_p = _TapComm(comm), _TapSteps(applied_action(task))
        traj = rollout(task, policy, tap_c, state.to(device), Rng([gen], device), task.horizon,
                       record=tap_p)
        agent = torch.stack([s[0] for s in tap_p.steps]).float().numpy()
        rel = torch.stack([s[1] for s in tap_p.steps]).float().numpy()
        masks = torch.stack([torch.stack(s[2]) for s in tap_p.steps]).numpy()  # (T, R, N, N)
        t, n = agent.shape[:2]
        if program is None:
            picks = _mask_picks(masks)
            uniform = np.zeros((t, rounds, 0, n, n), np.float32)
        else:
            picks, uniform = _program_arrays(program, tap_c.rounds, t, n)
        arrays.update({f"e{k}_agent": agent, f"e{k}_rel": rel, f"e{k}_picks": picks.astype(np.int64),
                       f"e{k}_uniform": uniform, f"e{k}_action": torch.stack([s[3] for s in tap_p.steps]).float()
                       .numpy(), f"e{k}_cost": traj.cost[:, 0].double().cpu().numpy()})
        meta.append({"episode": k, "eval_seed": seed, "steps": t, "agents": n,
                     "loss": float(traj.episode_metrics()["cost"][0])})
    return {"format": FORMAT, "episodes": meta, "rounds": rounds, "program": program is not None}, arrays


def _program_arrays(program: Program, taps: list, t: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The program's picks (T, R, N, K) and its random rules' uniforms (T, R, U, N, N) from the tapped rounds."""
    rounds = program.n_rounds
    k = max(1, max(len(rs) for rs in program.rounds))
    u = max(sum(isinstance(r, RandomRule) for r in rs) for rs in program.rounds)
    picks = np.full((t, rounds, n, k), -1, np.int64)
    uniform = np.zeros((t, rounds, u, n, n), np.float32)
    assert len(taps) == t * rounds, "one tapped call per step and round"
    for step in range(t):
        for r in range(rounds):
            p, draws = taps[step * rounds + r]
            picks[step, r, :, :p.shape[-1]] = p.numpy()
            for q, d in enumerate(draws):
                uniform[step, r, q] = d.numpy()
    return picks, uniform


@torch.no_grad()
def record_program(task: Task, comm: CommProvider, program: Program, episodes: int) -> tuple[dict, dict[str, np.ndarray]]:
    """Golden vectors of a program without a trained model: the first step of protocol episodes 0 .. episodes-1
    (no policy moves the agents further), picks and uniforms only."""
    arrays: dict[str, np.ndarray] = {}
    meta = []
    for k in range(episodes):
        state, gen, seed = protocol_episode(task, k)
        rng = Rng([gen], "cpu")
        obs = task.observe(state, rng)
        tap = _TapComm(comm)
        ctx = CommContext(task, state, obs, rng)
        for r in range(program.n_rounds):
            tap.picks(ctx, r)
        n = obs.agent.shape[1]
        picks, uniform = _program_arrays(program, tap.rounds, 1, n)
        arrays.update({f"e{k}_agent": obs.agent[:1].float().numpy(), f"e{k}_rel": obs.rel[:1].float().numpy(),
                       f"e{k}_picks": picks, f"e{k}_uniform": uniform})
        meta.append({"episode": k, "eval_seed": seed, "steps": 1, "agents": n})
    return {"format": FORMAT, "episodes": meta, "rounds": program.n_rounds, "program": True}, arrays
