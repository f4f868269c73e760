"""The dataset D of paper section 3.4: states visited by the oracle, with what it saw and did.

Rollouts of the trained transformer (eval mode, full soft attention), bucketed by agent count. Per kept step
(every ``stride``-th) it stores each agent's input, the noisy relative observations and the oracle's effective
action (the speed-clipped velocity, or the goal weights). Everything the objective needs besides the program
is derived from these tensors once, by the scorer.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from ..envs.base import MultiAgentEnv, Rng
from ..policy.comm import CommContext, FullComm
from ..policy.transformer import CommTransformer


@dataclass
class DataBucket:
    agent: Tensor  # (S, N, Ds) policy inputs s_i
    rel: Tensor  # (S, N, N, 2) observations o_ij
    target: Tensor  # (S, N, A) the oracle's effective action

    @property
    def states(self) -> int:
        return self.agent.shape[0]

    @property
    def n_agents(self) -> int:
        return self.agent.shape[1]


def collect(env: MultiAgentEnv, policy: CommTransformer, rollouts: int, stride: int, gen: torch.Generator,
            device: torch.device, chunk: int = 50) -> list[DataBucket]:
    """Roll out the oracle ``rollouts`` times (in chunks), keeping every ``stride``-th step."""
    by_n: dict[int, list[tuple[Tensor, Tensor, Tensor]]] = {}
    policy.eval()
    rng = Rng(gen, device)
    full = FullComm()
    with torch.no_grad():
        done = 0
        while done < rollouts:
            batch = min(chunk, rollouts - done)
            for bucket in env.reset(batch, gen):
                state = bucket.to(device)
                for t in range(env.horizon):
                    obs = env.observe(state, rng)
                    ctx = CommContext(env, state, obs, rng)
                    out = policy(obs, lambda logits, r: full.select(ctx, logits, r))
                    if t % stride == 0:
                        by_n.setdefault(state.n_agents, []).append(
                            (obs.agent.cpu(), obs.rel.cpu(), env.effective_action(out.action).cpu()))
                    state = env.step(state, out.action)
            done += batch
    return [DataBucket(*(torch.cat([x[k] for x in items]) for k in range(3))) for _, items in sorted(by_n.items())]


def to_payload(buckets: list[DataBucket]) -> dict:
    return {"format": "neurosym-dataset/1",
            "buckets": [{"agent": b.agent, "rel": b.rel, "target": b.target} for b in buckets]}


def from_payload(payload: dict) -> list[DataBucket]:
    return [DataBucket(b["agent"], b["rel"], b["target"]) for b in payload["buckets"]]
