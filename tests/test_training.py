"""The training loop: learning progress on a small case, and exact resume."""

import copy

import torch

from neurosym_cli.config import ModelConfig, TaskConfig
from neurosym_cli.envs import make_env
from neurosym_cli.evaluation import evaluate, summarize
from neurosym_cli.policy import CommTransformer, make_comm
from neurosym_cli.training import FitSpec, FitState, fit

SMALL = TaskConfig(name="two-groups-cross", num_groups=2, horizon=30, test_settings=["0", "1", "0-1"])


class Quiet:
    def update(self, step, total, metrics):
        pass


def _policy(env):
    torch.manual_seed(0)
    return CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig())


def test_loss_falls_on_a_small_case():
    env = make_env(SMALL)
    pol = _policy(env)
    comm = make_comm("full", 2)
    before = summarize(evaluate(env, pol, comm, range(4), torch.device("cpu")))["cost"]["mean"]
    spec = FitSpec(rollouts=16 * 25, batch=16, horizon=30, lr=1e-2, lr_final=1e-3)
    state = fit(pol, env, comm, spec, torch.Generator().manual_seed(0), torch.device("cpu"), Quiet(), lambda s: None)
    after = summarize(evaluate(env, pol, comm, range(4), torch.device("cpu")))["cost"]["mean"]
    assert state.step == 25
    first, last = state.history[0]["loss"], state.history[-1]["loss"]
    assert last < 0.8 * first, (first, last)
    assert after < 0.8 * before, (before, after)


def test_resume_reproduces_an_uninterrupted_run():
    env = make_env(SMALL)
    spec = FitSpec(rollouts=4 * 4, batch=4, horizon=10, checkpoint_every=2)
    comm = make_comm("full", 2)
    straight = _policy(env)
    fit(straight, env, comm, spec, torch.Generator().manual_seed(1), torch.device("cpu"), Quiet(), lambda s: None)

    resumed = _policy(env)
    saved = {}

    def save(st):
        if st.step == 2:
            saved["state"] = copy.deepcopy(st)
            saved["weights"] = copy.deepcopy(resumed.state_dict())

    half = FitSpec(**{**spec.__dict__})
    fit(resumed, env, comm, half, torch.Generator().manual_seed(1), torch.device("cpu"), Quiet(), save)
    # "crash" after step 2: rebuild from what the checkpoint held and continue with a fresh generator object
    fresh = _policy(env)
    fresh.load_state_dict(saved["weights"])
    torch.manual_seed(123)  # the global RNG is restored from the checkpoint, whatever it is now
    st: FitState = saved["state"]
    fit(fresh, env, comm, spec, torch.Generator().manual_seed(999), torch.device("cpu"), Quiet(), lambda s: None, st)
    for k, v in straight.state_dict().items():
        assert torch.allclose(v, fresh.state_dict()[k], atol=1e-6), k
