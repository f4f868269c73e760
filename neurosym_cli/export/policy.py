"""The transformer as files a robot can load without neurosym: TorchScript and ONNX, with whom each agent hears
given as input (the exported model never decides it) and the task's target (the speed clip, the goal softmax; of
the action and the agent's own input s_i) inside, so the output is the action as the task applies it.

    policy.pt / policy.onnx   the team in one call: agent (B, N, Ds), rel (B, N, N, Dp), picks (B, R, N, K) int64
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

import io
import warnings
from pathlib import Path

import torch
from torch import Tensor, nn

from ..dsl.interpret import dedup_valid_traced
from ..policy.transformer import CommTransformer
from ..tasks.base import Target
from ..utils.io import atomic_write_bytes

OPSET = 17
"""ONNX opset of every exported graph (onnxruntime >= 1.14 runs it)"""

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


def _onnx(module: nn.Module, args: tuple, names: list[str], dynamic: dict[str, dict[int, str]],
          out: str | list[str], path: Path) -> None:
    buf = io.BytesIO()
    with warnings.catch_warnings():  # the tracer's notes are expected (shapes read as ints, the legacy exporter)
        warnings.simplefilter("ignore")
        torch.onnx.export(module.eval(), args, buf, dynamo=False, opset_version=OPSET, input_names=names,
                          output_names=[out] if isinstance(out, str) else out, dynamic_axes=dynamic)
    atomic_write_bytes(path, buf.getvalue())


def export_policy(policy: CommTransformer, target: Target, agent: Tensor, rel: Tensor, picks: Tensor,
                  folder: Path) -> list[str]:
    """Write policy.pt, policy.onnx and agent/*.onnx, traced on one real input (agent (1, N, Ds), rel (1, N, N, Dp),
    picks (1, R, N, K)); returns the files written, relative to ``folder``."""
    policy = policy.cpu().eval()
    team = TeamPolicy(policy, target).eval()
    args = (agent.cpu(), rel.cpu(), picks.cpu())
    with warnings.catch_warnings(), torch.no_grad():
        warnings.simplefilter("ignore")
        traced = torch.jit.trace(team, args, check_trace=False)
    buf = io.BytesIO()
    with warnings.catch_warnings():  # TorchScript is deprecated in favour of torch.export, still what robots load
        warnings.simplefilter("ignore")
        torch.jit.save(traced, buf)
    atomic_write_bytes(folder / "policy.pt", buf.getvalue())
    _onnx(team, args, ["agent", "rel", "picks"],
          {"agent": {0: "B", 1: "N"}, "rel": {0: "B", 1: "N", 2: "N"}, "picks": {0: "B", 2: "N", 3: "K"},
           "action": {0: "B", 1: "N"}, "raw": {0: "B", 1: "N"}}, ["action", "raw"], folder / "policy.onnx")
    files = ["policy.pt", "policy.onnx"]
    d = policy.embed.out_features
    s = agent[0].cpu()  # (N, Ds): N rows as M agents
    n, k, p = s.shape[0], picks.shape[-1], rel.shape[-1]
    x = torch.zeros(n, d)
    _onnx(AgentEncode(policy), (s,), ["s"], {"s": {0: "M"}, "h": {0: "M"}}, "h", folder / "agent" / "encode.onnx")
    files.append("agent/encode.onnx")
    for r in range(policy.n_rounds):
        _onnx(AgentMessage(policy, r), (x, rel[0, :, 0].cpu()), ["x", "o_ji"], {"x": {0: "M"}, "o_ji": {0: "M"},
              "m": {0: "M"}}, "m", folder / "agent" / f"message{r + 1}.onnx")
        _onnx(AgentReceive(policy, r), (x, x, torch.zeros(n, k, p), torch.zeros(n, k, d),
                                        torch.ones(n, k, dtype=torch.bool)),
              ["x", "h", "o_ij", "m", "valid"],
              {"x": {0: "M"}, "h": {0: "M"}, "o_ij": {0: "M", 1: "K"}, "m": {0: "M", 1: "K"},
               "valid": {0: "M", 1: "K"}, "y": {0: "M"}}, "y", folder / "agent" / f"receive{r + 1}.onnx")
        files += [f"agent/message{r + 1}.onnx", f"agent/receive{r + 1}.onnx"]
    _onnx(AgentAct(policy, target), (x, s), ["y", "s"], {"y": {0: "M"}, "s": {0: "M"}, "action": {0: "M"},
                                                      "raw": {0: "M"}},
          ["action", "raw"],
          folder / "agent" / "act.onnx")
    files.append("agent/act.onnx")
    return files
