"""examples/consensus, the example where communication matters: 4-wide observations that the policy takes, a cost
averaged over agents, and the reason to communicate: averaging the others' estimates of the goal (what a message
carries) brings the agents closer to it than each agent's own estimate does, and knowing the goal closer still."""

import pytest
import torch

from conftest import ROOT


@pytest.fixture
def consensus(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "examples" / "consensus"))
    import consensus

    return consensus


def _episode_cost(task, heard, state, gen):
    """Time-averaged cost (B,) when every agent flies to the mean goal estimate of itself and the agents it hears:
    heard (N, N) bool, or None for the true goal. Estimates are read from the observations alone (s_j and o_ij),
    as a message would carry them."""
    from neurosym import Rng

    rng, total = Rng(gen), 0.0
    for _ in range(task.horizon):
        obs = task.observe(state, rng)
        if heard is None:
            target = state.goal - state.pos
        else:
            eye = torch.eye(task.n, dtype=torch.bool)
            mine = obs.agent[..., :2]  # g^_i - x_i
            off = obs.rel[..., :2] * ~eye[..., None]  # [i, j] = x_j - x_i (0 on the diagonal, where o_ii is noise)
            theirs = mine[:, None, :, :] + off  # [i, j] = (g^_j - x_j) + (x_j - x_i): j's estimate, from i
            w = (heard | eye).float()
            target = (w[None, :, :, None] * theirs).sum(2) / w.sum(-1)[None, :, None]
        action = target / task.cfg.dt
        state = task.step(state, action)
        total = total + task.cost(state, action)
    return total / task.horizon


def test_hearing_others_estimates_beats_ones_own_and_the_true_goal_beats_both(consensus):
    task = consensus.ConsensusTask(consensus.ConsensusConfig())  # the example's defaults: N = 12, T = 30
    n = task.n
    state = task.reset(64, torch.Generator().manual_seed(0))[0]
    nobody = torch.zeros(n, n, dtype=torch.bool)
    everybody = ~torch.eye(n, dtype=torch.bool)
    two = torch.zeros(n, n, dtype=torch.bool)
    idx = torch.arange(n)
    two[idx, (idx + 1) % n] = two[idx, (idx + 2) % n] = True  # each hears its next two: degree 4
    cost = {k: _episode_cost(task, h, state, torch.Generator().manual_seed(1)).mean().item()
            for k, h in [("own", nobody), ("two", two), ("all", everybody), ("goal", None)]}
    assert cost["goal"] < cost["all"] < cost["two"] < cost["own"], cost
    # the gap the example is built on: everyone's average is over 10 % below going alone (the rest of the loss is
    # the flight, the same for all), and two others close more than half of that gap (examples/consensus/README.md)
    assert cost["own"] - cost["all"] > 0.1 * cost["own"], cost
    assert cost["own"] - cost["two"] > 0.5 * (cost["own"] - cost["all"]), cost
    # with exact estimates there is nothing to learn from others
    exact = consensus.ConsensusTask(consensus.ConsensusConfig(estimate_std=0.0, noise_std=0.0))
    s0 = exact.reset(8, torch.Generator().manual_seed(0))[0]
    own, all_ = (_episode_cost(exact, h, s0, torch.Generator().manual_seed(1)) for h in (nobody, everybody))
    assert torch.allclose(own, all_, atol=1e-5)


def test_the_widths_reach_the_policy_and_the_gradient_reaches_its_weights(consensus):
    """Ds = Dp = 4 from the task: the transformer built for it runs a step under full communication, and the cost
    (a mean over agents, which the figures' axes say) backpropagates into the edge weights that read o_ij."""
    from neurosym_cli.config import ModelConfig
    from neurosym_cli.policy.transformer import CommTransformer
    from neurosym_cli.tasks.base import cost_words

    cfg = consensus.ConsensusConfig()
    task = consensus.ConsensusTask(cfg)
    assert (task.obs_dim, task.pair_dim, task.action_dim) == (4, 4, 2)
    assert cost_words(cfg) == "averaged over agents"
    torch.manual_seed(0)
    pol = CommTransformer.for_task(task, ModelConfig())
    assert pol.rounds[0].key_edge.in_features == 4 and pol.rounds[0].msg_edge.in_features == 4
    from neurosym import Rng

    state = task.reset(3, torch.Generator().manual_seed(0))[0]
    obs = task.observe(state, Rng(torch.Generator().manual_seed(1)))
    everybody = ~torch.eye(task.n, dtype=torch.bool).expand(3, -1, -1)
    out = pol(obs, lambda logits, r: everybody)
    assert out.action.shape == (3, task.n, 2)
    task.cost(task.step(state, out.action), out.action).sum().backward()
    g = pol.rounds[0].msg_edge.weight.grad
    assert g is not None and torch.isfinite(g).all() and g.abs().sum() > 0


def test_a_negative_estimate_error_is_one_line(consensus):
    from neurosym import ConfigError

    with pytest.raises(ConfigError, match="task.estimate_std must be non-negative"):
        consensus.ConsensusConfig(estimate_std=-1.0)
