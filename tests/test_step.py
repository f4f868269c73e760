"""The one step function: rollout, episode recording, dataset collection and the golden vectors of export all run
the same step, and each gives what a step written out here on its own gives, bit for bit."""

import numpy as np
import pytest
import torch

from neurosym_cli.config import ModelConfig
from neurosym_cli.episode import protocol_episode, record_episode
from neurosym_cli.export.golden import record as golden
from neurosym_cli.policy import CommTransformer
from neurosym_cli.policy.comm import CommContext, FullComm
from neurosym_cli.rollout import rollout
from neurosym_cli.synth.dataset import collect
from neurosym_cli.tasks import make_task
from neurosym_cli.tasks.base import Rng
from neurosym_cli.tasks.random_cross import CrossConfig

CPU = torch.device("cpu")
# a random rule: its draws come from the episode's random source, between the observation noise of the steps
PROGRAM = "argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nrandom(filter(d >= 3.41, l))\n"


def _written_out(env, policy, comm, state, rng, horizon):
    """observe -> context -> policy -> dynamics -> cost, as the paper's loop reads, without the package's step ->
    per step (B, ...) tensors: agent, rel, target (the applied action), pos (after the step), cost."""
    rows = []
    with torch.no_grad():
        for t in range(horizon):
            obs = env.observe(state, rng)
            ctx = CommContext(env, state, obs, rng, t)
            out = policy(obs, lambda logits, r: comm.select(ctx, logits, r), lambda r: comm.picks(ctx, r))
            state = env.step(state, out.action)
            rows.append({"agent": obs.agent, "rel": obs.rel, "target": env.target(out.action), "pos": state.pos,
                         "cost": env.cost(state, out.action)})
    return {k: torch.stack([r[k] for r in rows]) for k in rows[0]}  # (T, B, ...)


def _program():
    from fixtures import feature_map

    from neurosym_cli.dsl.parser import parse
    from neurosym_cli.policy.comm import ProgramComm

    return ProgramComm(parse(PROGRAM), feature_map("formation"))


@pytest.fixture(scope="module")
def team():
    task = CrossConfig(name="two-groups-cross", _target_="neurosym_cli.tasks.two_groups_cross.TwoGroupsCrossTask",
                       num_groups=2, agents_per_group=4, test_settings=["0", "0-1"])
    env = make_task(task, 10)
    torch.manual_seed(0)
    return env, CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig(width=16, ffn=32)).eval()


@pytest.mark.parametrize("scheme", ["full", "program"])
def test_rollout_episode_and_golden_run_the_written_out_step(team, scheme):
    env, policy = team
    comm = FullComm() if scheme == "full" else _program()
    state, gen, _ = protocol_episode(env, 1)
    want = _written_out(env, policy, comm, state, Rng([gen]), env.horizon)

    state, gen, _ = protocol_episode(env, 1)
    with torch.no_grad():
        traj = rollout(env, policy, comm, state, Rng([gen]), env.horizon)
    assert torch.equal(traj.cost, want["cost"])

    state, gen, _ = protocol_episode(env, 1)
    rec = record_episode(env, policy, comm, state, gen, CPU)
    assert np.array_equal(rec.pos[1:], want["pos"][:, 0].numpy())
    assert np.array_equal(rec.inputs, want["agent"][:, 0].numpy())
    assert np.array_equal(rec.cost, want["cost"][:, 0].double().numpy())
    assert (rec.picks is not None) == (scheme == "program")

    _, arrays = golden(env, policy, comm, comm.program if scheme == "program" else None, 2, CPU)
    assert np.array_equal(arrays["e1_action"], want["target"][:, 0].numpy())
    assert np.array_equal(arrays["e1_rel"], want["rel"][:, 0].numpy())
    assert np.array_equal(arrays["e1_cost"], want["cost"][:, 0].double().numpy())


def test_the_dataset_holds_the_written_out_rollouts_every_stride_th_step():
    env = make_task(CrossConfig(name="random-cross", horizon=7))
    torch.manual_seed(0)
    policy = CommTransformer(env.obs_dim, env.action_dim, 2, ModelConfig()).eval()
    data = collect(env, policy, 5, 3, torch.Generator().manual_seed(4), CPU, chunk=3)

    gen = torch.Generator().manual_seed(4)  # the same draws in the same order: chunks of 3 and 2 rollouts
    rng, by_n = Rng(gen), {}
    for batch in (3, 2):
        for bucket in env.reset(batch, gen):
            rows = _written_out(env, policy, FullComm(), bucket, rng, env.horizon)
            by_n.setdefault(bucket.n_agents, []).append({k: v[::3].flatten(0, 1) for k, v in rows.items()})
    assert len(data) == len(by_n) and sum(b.states for b in data) == 5 * 3  # steps 0, 3, 6 of each rollout
    for bucket, (_, parts) in zip(data, sorted(by_n.items())):
        for field, key in (("agent", "agent"), ("rel", "rel"), ("target", "target")):
            assert torch.equal(getattr(bucket, field), torch.cat([p[key] for p in parts]))
