"""The dataset D of paper section 3.4: states visited by the oracle, with what it saw and did.

Rollouts of the trained transformer (eval mode, full soft attention), bucketed by agent count. Per kept step
(every ``stride``-th) it stores each agent's input, the noisy relative observations and the oracle's effective
action (the speed-clipped velocity, or the goal weights). Everything the objective needs besides the program
is derived from these tensors once, by the scorer.
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass
from pathlib import Path

import torch
from torch import Tensor

from ..run.checkpoints import load_payload, non_finite, save_checkpoint
from ..tasks.base import Rng, Task, applied_action
from ..utils.console import log
from ..utils.io import ArtifactError
from ..policy.comm import FullComm
from ..policy.transformer import CommTransformer
from ..rollout import rollout
from ..step import Step


@dataclass
class DataBucket:
    agent: Tensor  # (S, N, Ds) policy inputs s_i
    rel: Tensor  # (S, N, N, 2) observations o_ij
    target: Tensor  # (S, N, A) the oracle's effective action (Task.target of its action and s_i)

    @property
    def states(self) -> int:
        return self.agent.shape[0]

    @property
    def n_agents(self) -> int:
        return self.agent.shape[1]


def collect(env: Task, policy: CommTransformer, rollouts: int, stride: int, gen: torch.Generator,
            device: torch.device, chunk: int = 50) -> list[DataBucket]:
    """Roll out the oracle ``rollouts`` times (in chunks), keeping every ``stride``-th step."""
    by_n: dict[int, list[tuple[Tensor, Tensor, Tensor]]] = {}
    applied = applied_action(env)

    def keep(s: Step) -> None:
        if s.t % stride == 0:
            by_n.setdefault(s.state.n_agents, []).append(
                (s.obs.agent.cpu(), s.obs.rel.cpu(), applied(s.out.action, s.obs.agent).cpu()))

    policy.eval()
    rng = Rng(gen, device)
    full = FullComm()
    with torch.no_grad():
        done = 0
        while done < rollouts:
            batch = min(chunk, rollouts - done)
            for bucket in env.reset(batch, gen):
                rollout(env, policy, full, bucket.to(device), rng, env.horizon, stats=False, record=keep)
            done += batch
    return [DataBucket(*(torch.cat([x[k] for x in items]) for k in range(3))) for _, items in sorted(by_n.items())]


def subsample(buckets: list[DataBucket], every: int) -> list[DataBucket]:
    """Every ``every``-th state of each bucket (the coarse scorer of the restarts, synth.coarse)."""
    return [DataBucket(b.agent[::every], b.rel[::every], b.target[::every]) for b in buckets]


FORMAT = "neurosym-dataset/1"


def to_payload(buckets: list[DataBucket]) -> dict:
    return {"format": FORMAT,
            "buckets": [{"agent": b.agent, "rel": b.rel, "target": b.target} for b in buckets]}


def from_payload(payload: dict) -> list[DataBucket]:
    return [DataBucket(b["agent"], b["rel"], b["target"]) for b in payload["buckets"]]


def fingerprint(policy: CommTransformer) -> str:
    """Identifies the oracle's weights, so a dataset collected from other weights is never reused."""
    h = hashlib.sha1()
    for k, v in sorted(policy.state_dict().items()):
        h.update(k.encode())
        h.update(v.detach().cpu().contiguous().numpy().tobytes())
    return h.hexdigest()


def load_or_collect(path: Path, made_by: str, env: Task, policy: CommTransformer, *, rollouts: int, stride: int,
                    gen: torch.Generator, device: torch.device, oracle_by: str = "neurosym train") -> list[DataBucket]:
    """The dataset D at ``path`` when it was collected from these oracle weights, else collected and saved there
    (once per oracle, rollouts and stride: every synthesis run of a sweep reuses it). A D with a nan or inf is
    never used: a saved one is collected again, a collected one is an error naming ``oracle_by``, the command that
    trains the oracle."""
    oracle = fingerprint(policy)
    if Path(path).exists():
        try:
            payload = load_payload(path, made_by, FORMAT, "dataset")
        except ArtifactError as e:
            log.warning("%s; collecting it again", e)
        else:
            bad = non_finite(payload.get("buckets"), "buckets")
            if bad:  # a nan in D scores every program nan: never searched on
                log.warning("the dataset %s holds non-finite values (%s); collecting it again", path, bad)
            elif payload.get("oracle") == oracle:
                log.info("reusing the dataset %s", path)
                return from_payload(payload)
            else:
                log.info("the dataset %s came from other oracle weights; collecting it again", path)
    t0 = time.perf_counter()
    data = collect(env, policy, rollouts, stride, gen, device)
    bad = non_finite(to_payload(data)["buckets"], "buckets")
    if bad:
        raise ArtifactError(f"the oracle's rollouts reached non-finite values ({bad}; nothing saved): its weights "
                            f"are finite but its task diverges; `{oracle_by} "
                            "overwrite=true` with a smaller optim.lr, or smaller task scales (task.dt, task.v_max)")
    save_checkpoint(path, {**to_payload(data), "oracle": oracle})
    pairs = sum(b.states * b.n_agents ** 2 for b in data)
    log.info("collected D: %d rollouts, %d states, %.1fM agent pairs in %.0f s -> %s", rollouts,
             sum(b.states for b in data), pairs / 1e6, time.perf_counter() - t0, path)
    return data
