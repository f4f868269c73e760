"""The transformer as functions a robot can load without neurosym, with whom each agent hears given as input (the
exported model never decides it) and the task's target (the speed clip, the goal softmax; of the action and the
agent's own input s_i) inside, so the output is the action as the task applies it. Each is a ``Graph``: the module,
the recorded inputs it is traced on, and the names and free axes of its inputs and outputs; formats.py writes them
as TorchScript, torch.export and ONNX files.

    policy.*                  the team in one call: agent (B, N, Ds), rel (B, N, N, Dp), picks (B, R, N, K) int64
                              (-1 = nobody; an agent picked twice counts once) -> action (B, N, A) as applied,
                              and raw (B, N, A), the transformer's output before Task.target (what a simulator's
                              Task.step takes)
    agent/*.onnx              the same function cut where the messages travel, for one agent on its own (M rows of
                              agents at once): encode, per round message (the sender's side) and receive (the
                              receiver's side), act. docs/deploy.md has the message flow.

Both are traced through the transformer's own sparse path (CommRound.picked_round, receive, message), so the
exported function is the one evaluation runs, up to float rounding.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import torch
from torch import Tensor, nn

from ..dsl.interpret import dedup_valid_traced
from ..policy.transformer import CommTransformer
from ..tasks.base import Target
from ..utils.ops import SOFTMAX_WRITTEN_OUT_BELOW

Axes = tuple  # of str | None
"""per axis of a tensor the name of its free size (B, N, K, M), or None where the size is fixed"""


@dataclass(frozen=True)
class Graph:
    """One function to export: ``file`` its path without the suffix ("policy", "agent/encode"), the module, the
    example inputs it is traced on, its inputs' and outputs' names with their Axes (in order), and the bounds
    [low, high] (high None: unbounded) of a free size the traced function holds only within."""

    file: str
    module: nn.Module
    args: tuple
    inputs: dict
    outputs: dict
    bounds: dict = field(default_factory=dict)


def k_bounds(k: int) -> tuple[int, int | None]:
    """The K (picks per agent) a graph traced at ``k`` serves: softmax_last's form is chosen by K when traced, so
    [1, 15] when traced below 16, else [16, unbounded)."""
    cut = SOFTMAX_WRITTEN_OUT_BELOW
    return (1, cut - 1) if k < cut else (cut, None)


class TeamPolicy(nn.Module):
    """agent (B, N, Ds), rel (B, N, N, Dp), picks (B, R, N, K) long -> (target action, raw action), (B, N, A) each."""

    def __init__(self, policy: CommTransformer, target: Target):
        super().__init__()
        self.policy, self.target = policy, target

    def forward(self, agent: Tensor, rel: Tensor, picks: Tensor) -> tuple[Tensor, Tensor]:
        h = torch.relu(self.policy.embed(agent))
        x = h
        for r, layer in enumerate(self.policy.rounds):
            pk = picks[:, r]
            x, _ = layer.picked_round(x, h, rel, pk, dedup_valid_traced(pk))
        raw = self.policy.head(x)
        return self.target(raw, agent), raw


class AgentEncode(nn.Module):
    """s (M, Ds) one agent's own input per row -> h (M, D) its state embedding, also its round-1 input x."""

    def __init__(self, policy: CommTransformer):
        super().__init__()
        self.embed = policy.embed

    def forward(self, s: Tensor) -> Tensor:
        return torch.relu(self.embed(s))


class AgentMessage(nn.Module):
    """The sender's side of one round: x (M, D) the sender's round input, o_ji (M, Dp) its view of the receiver ->
    the message (M, D)."""

    def __init__(self, policy: CommTransformer, r: int):
        super().__init__()
        self.layer = policy.rounds[r]

    def forward(self, x: Tensor, o_ji: Tensor) -> Tensor:
        return self.layer.message(self.layer.value(x), o_ji)


class AgentReceive(nn.Module):
    """The receiver's side of one round: x (M, D) its round input, h (M, D) its embedding, o_ij (M, K, Dp) its
    views of the K agents it asked, m (M, K, D) their messages, valid (M, K) bool the slots that count -> its
    round output (M, D), the next round's input."""

    def __init__(self, policy: CommTransformer, r: int):
        super().__init__()
        self.layer = policy.rounds[r]

    def forward(self, x: Tensor, h: Tensor, o_ij: Tensor, m: Tensor, valid: Tensor) -> Tensor:
        return self.layer.receive(x, h, o_ij, m, valid)[0]


class AgentAct(nn.Module):
    """y (M, D) the last round's output, s (M, Ds) the agent's own input (the task's target may read it) -> (the
    target action, the raw action), (M, A) each."""

    def __init__(self, policy: CommTransformer, target: Target):
        super().__init__()
        self.head, self.target = policy.head, target

    def forward(self, y: Tensor, s: Tensor) -> tuple[Tensor, Tensor]:
        raw = self.head(y)
        return self.target(raw.unsqueeze(0), s.unsqueeze(0))[0], raw  # targets are written for (B, N, A)


def policy_graphs(policy: CommTransformer, target: Target, agent: Tensor, rel: Tensor, picks: Tensor
                  ) -> tuple[Graph, list[Graph]]:
    """(the team in one call, the per-agent pieces), traced on one recorded episode: agent (T, N, Ds), rel (T, N, N,
    Dp), picks (T, R, N, K) with the steps as the batch. The examples hold at least two steps and two picks (a
    padded pick is -1, nobody): a free size traced at 1 would be fixed at 1."""
    policy = policy.cpu().eval()
    agent, rel, picks = agent.cpu(), rel.cpu(), picks.cpu()
    if agent.shape[0] < 2:
        agent, rel, picks = (torch.cat([t, t]) for t in (agent, rel, picks))
    if picks.shape[-1] < 2:
        picks = torch.cat([picks, torch.full_like(picks[..., :1], -1)], -1)
    bounds = {"K": k_bounds(picks.shape[-1])}
    team = Graph("policy", TeamPolicy(policy, target).eval(), (agent, rel, picks),
                 {"agent": ("B", "N", None), "rel": ("B", "N", "N", None), "picks": ("B", None, "N", "K")},
                 {"action": ("B", "N", None), "raw": ("B", "N", None)}, bounds)
    d = policy.embed.out_features
    s = agent[0]  # (N, Ds): N rows as M agents
    n, k, p = s.shape[0], picks.shape[-1], rel.shape[-1]
    x = torch.zeros(n, d)
    m = ("M", None)
    pieces = [Graph("agent/encode", AgentEncode(policy).eval(), (s,), {"s": m}, {"h": m})]
    for r in range(policy.n_rounds):
        pieces.append(Graph(f"agent/message{r + 1}", AgentMessage(policy, r).eval(), (x, rel[0, :, 0]),
                            {"x": m, "o_ji": m}, {"m": m}))
        pieces.append(Graph(f"agent/receive{r + 1}", AgentReceive(policy, r).eval(),
                            (x, x.clone(), torch.zeros(n, k, p), torch.zeros(n, k, d),  # x, h apart: one tensor
                             torch.ones(n, k, dtype=torch.bool)),  # given twice is one input to torch.export
                            {"x": m, "h": m, "o_ij": ("M", "K", None), "m": ("M", "K", None), "valid": ("M", "K")},
                            {"y": m}, bounds))
    pieces.append(Graph("agent/act", AgentAct(policy, target).eval(), (x, s), {"y": m, "s": m},
                        {"action": m, "raw": m}))
    return team, pieces
