"""Transformer and communication providers: shapes, masks respected, decentralised attention, degrees."""

import torch

from neurosym_cli.config import ModelConfig
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.tasks import Observation, Rng, make_task
from neurosym_cli.tasks.formation import FormationState
from neurosym_cli.policy import CommContext, CommTransformer, FullComm, NearestComm, NoComm, TopKComm
from neurosym_cli.rollout import degree_stats, rollout


def _policy(rounds=1, obs_dim=2, action_dim=2):
    torch.manual_seed(0)
    p = CommTransformer(obs_dim, action_dim, rounds, ModelConfig(dropout=0.0))
    return p.eval()


def _obs(b=2, n=5, obs_dim=2, seed=0):
    g = torch.Generator().manual_seed(seed)
    return Observation(torch.randn(b, n, obs_dim, generator=g), torch.randn(b, n, n, 2, generator=g))


def _fixed(mask):
    return lambda logits, r: mask.expand_as(logits)


def test_shapes_and_attention_rows():
    pol = _policy(rounds=2, obs_dim=22, action_dim=10)
    obs = _obs(3, 6, 22)
    out = pol(obs, lambda logits, r: ~torch.eye(6, dtype=torch.bool).expand_as(logits))
    assert out.action.shape == (3, 6, 10)
    assert len(out.attn) == 2 and out.attn[0].shape == (3, 6, 6)
    assert torch.allclose(out.attn[0].sum(-1), torch.ones(3, 6), atol=1e-5)
    assert (out.attn[0].diagonal(dim1=1, dim2=2) == 0).all()


def test_unheard_agent_changes_nothing_for_others():
    pol = _policy()
    n = 5
    mask = ~torch.eye(n, dtype=torch.bool)
    mask[:, 3] = False  # nobody hears agent 3
    obs = _obs(1, n)
    base = pol(obs, _fixed(mask)).action
    agent = obs.agent.clone()
    agent[0, 3] += 10.0  # change agent 3's private state (its messages)
    rel = obs.rel.clone()
    rel[0, 3] += 5.0  # and agent 3's views of others (the edge part of its messages)
    moved = pol(Observation(agent, rel), _fixed(mask)).action
    others = [0, 1, 2, 4]
    assert torch.allclose(base[0, others], moved[0, others], atol=1e-6)
    assert not torch.allclose(base[0, 3], moved[0, 3])
    # but when agent 3 is heard, the same change does move the others
    full = ~torch.eye(n, dtype=torch.bool)
    assert not torch.allclose(pol(obs, _fixed(full)).action[0, others],
                              pol(Observation(agent, rel), _fixed(full)).action[0, others])


def test_attention_logits_are_decentralised():
    """l_ij depends only on (s_i, o_ij): changing another agent's private state leaves agent i's logits alone."""
    pol = _policy()
    obs = _obs(1, 4)
    seen = {}
    pol(obs, lambda logits, r: seen.setdefault("a", logits) is None or ~torch.eye(4, dtype=torch.bool).expand_as(logits))
    agent = obs.agent.clone()
    agent[0, 2] += 3.0
    pol(Observation(agent, obs.rel), lambda logits, r: seen.setdefault("b", logits) is None or ~torch.eye(4, dtype=torch.bool).expand_as(logits))
    rows = [0, 1, 3]
    assert torch.allclose(seen["a"][0, rows], seen["b"][0, rows])
    assert not torch.allclose(seen["a"][0, 2], seen["b"][0, 2])


def test_empty_row_gives_zero_attention_and_finite_gradients():
    pol = _policy()
    pol.train()
    obs = _obs(1, 4)
    out = pol(obs, _fixed(torch.zeros(4, 4, dtype=torch.bool)))
    assert (out.attn[0] == 0).all()
    out.action.sum().backward()
    assert all(torch.isfinite(p.grad).all() for p in pol.parameters() if p.grad is not None)


def _ctx(n=6, seed=0):
    env = make_task(CrossConfig(name="c", noise_std=0.0))
    g = torch.Generator().manual_seed(seed)
    pos = torch.randn(2, n, 2, generator=g) * 3
    state = FormationState(pos, pos.clone(), torch.zeros(2, n, dtype=torch.long))
    obs = env.observe(state, Rng(g))
    return CommContext(env, state, obs, Rng(g)), torch.randn(2, n, n, generator=g)


def test_providers_degrees():
    ctx, logits = _ctx()
    full = FullComm().select(ctx, logits, 0)
    assert full.sum(-1).eq(5).all() and not full.diagonal(dim1=1, dim2=2).any()
    assert not NoComm().select(ctx, logits, 0).any()
    top = TopKComm(2).select(ctx, logits, 0)
    assert top.sum(-1).eq(2).all() and not top.diagonal(dim1=1, dim2=2).any()
    masked = logits.clone()
    masked.diagonal(dim1=1, dim2=2).fill_(float("-inf"))
    assert torch.equal(top.nonzero(), torch.zeros_like(top).scatter(-1, masked.topk(2, -1).indices, True).nonzero())
    near = NearestComm(3).select(ctx, logits, 0)
    d = torch.cdist(ctx.state.pos, ctx.state.pos) + torch.eye(6) * 1e9
    assert torch.equal(near, torch.zeros_like(near).scatter(-1, d.topk(3, -1, largest=False).indices, True))
    assert TopKComm(10).select(ctx, logits, 0).sum(-1).eq(5).all()  # k larger than N - 1: everybody else


def test_degree_stats_on_hand_built_graphs():
    # star: everybody hears agent 0; agent 0 hears nobody
    star = torch.zeros(1, 4, 4, dtype=torch.bool)
    star[0, 1:, 0] = True
    mi, mo, md, mean = degree_stats([star])
    assert (float(mi), float(mo), float(md), float(mean)) == (1.0, 3.0, 3.0, 1.5)
    # directed ring: in = out = 1 for all
    ring = torch.zeros(1, 4, 4, dtype=torch.bool)
    ring[0, torch.arange(4), (torch.arange(4) + 1) % 4] = True
    mi, mo, md, mean = degree_stats([ring])
    assert (float(mi), float(mo), float(md), float(mean)) == (1.0, 1.0, 2.0, 2.0)
    # two rounds are averaged
    mi, mo, _, _ = degree_stats([star, ring])
    assert (float(mi), float(mo)) == (1.0, 2.0)


def test_rollout_records_degrees_and_costs(gen):
    env = make_task(CrossConfig(name="c", horizon=4, test_settings=[]))
    pol = _policy()
    s = env.reset(3, gen)
    for b in s:
        traj = rollout(env, pol, TopKComm(2), b, Rng(gen), 4)
        assert traj.cost.shape == (4, b.batch)
        assert (traj.max_in == 2).all() and (traj.max_out >= 2).all()
        m = traj.episode_metrics()
        assert set(m) >= {"cost", "max_in", "max_out", "mean_degree", "collisions"}


def test_sparse_picks_path_equals_dense_path_values_and_gradients():
    """Giving the selection as picks (repeats and -1 included) computes the same function as the dense mask."""
    from neurosym_cli.dsl.interpret import picks_to_mask

    pol = _policy(rounds=2)
    b, n = 3, 7
    obs = _obs(b, n)
    g = torch.Generator().manual_seed(1)
    picks = torch.randint(-1, n, (b, n, 3), generator=g)
    picks[..., 2] = picks[..., 0]  # a repeated pick counts once
    picks[0, 0] = -1  # agent 0 of episode 0 hears nobody
    eye = torch.arange(n).view(1, n, 1)
    picks = torch.where(picks == eye, -1, picks)  # nobody picks itself
    mask = picks_to_mask(picks, n)
    grads = []
    for sparse in (False, True):
        obs_g = Observation(obs.agent.clone().requires_grad_(), obs.rel.clone().requires_grad_())
        pol.zero_grad()
        out = pol(obs_g, _fixed(mask), (lambda r: picks) if sparse else None)
        out.action.square().sum().backward()
        grads.append((out, obs_g.agent.grad, obs_g.rel.grad, pol.rounds[0].key_edge.weight.grad.clone()))
    (dense, *gd), (sparse, *gs) = grads
    assert torch.equal(sparse.masks[1], mask)
    assert torch.allclose(sparse.action, dense.action, atol=1e-5)
    assert torch.allclose(sparse.attn[0], dense.attn[0], atol=1e-6)
    for a, c in zip(gd, gs):
        assert torch.allclose(a, c, atol=1e-5)


def test_providers_give_picks_matching_their_masks(gen):
    env = make_task(CrossConfig(name="random-cross", noise_std=0.0))
    s = env.reset(6, gen)[0]
    obs = env.observe(s, Rng(gen, torch.device("cpu")))
    ctx = CommContext(env, s, obs, Rng(gen, torch.device("cpu")))
    logits = torch.zeros(s.batch, s.n_agents, s.n_agents)
    from neurosym_cli.dsl.interpret import picks_to_mask

    for comm in (NoComm(), NearestComm(3)):
        assert torch.equal(picks_to_mask(comm.picks(ctx, 0), s.n_agents), comm.select(ctx, logits, 0))
    assert FullComm().picks(ctx, 0) is None and TopKComm(2).picks(ctx, 0) is None
    assert NoComm().picks(ctx, 0).shape == (s.batch, s.n_agents, 0)
