"""The sparse path of large teams (tasks/pairs.py, policy/scan.py): the cell list's collision ramps and counts equal
the dense ones (values and gradients), the counter-based noise is deterministic and normal, and the sparse path
gives the dense path's picks, actions and costs on small teams."""

import dataclasses

import pytest
import torch

from neurosym_cli.config import ModelConfig
from neurosym_cli.dsl.parser import parse
from neurosym_cli.policy.comm import CommContext, LinkFailure, NearestComm, NoComm, ProgramComm
from neurosym_cli.policy.transformer import CommTransformer, Heard
from neurosym_cli.rollout import degree_stats, rollout
from neurosym_cli.tasks import pairs
from neurosym_cli.tasks.base import Observation, Rng
from neurosym_cli.tasks.formation import FormationState
from neurosym_cli.tasks.random_cross import CrossConfig, RandomCrossTask

CROSS = CrossConfig(name="random-cross", group_prob=1.0)


def _cross(sparse_from):
    return RandomCrossTask(dataclasses.replace(CROSS, sparse_from=sparse_from))


def _scattered(b, n, spread, seed=0, dtype=torch.float64):
    g = torch.Generator().manual_seed(seed)
    pos = (torch.rand(b, n, 2, generator=g, dtype=dtype) * spread).requires_grad_()
    return FormationState(pos, torch.zeros_like(pos.detach()), torch.randint(0, 4, (b, n), generator=g))


def test_close_pairs_are_exactly_the_pairs_within_the_radius():
    s = _scattered(3, 300, 12.0)
    for radius in (0.1, 0.7, 4.0):
        first, second = pairs.close_pairs(s.pos, radius)
        got = set(zip(first.tolist(), second.tolist()))
        d = torch.cdist(s.pos.detach(), s.pos.detach())
        b, i, j = torch.nonzero((d < radius) & torch.ones(300, 300, dtype=torch.bool).triu(1), as_tuple=True)
        assert got == set(zip((b * 300 + i).tolist(), (b * 300 + j).tolist()))
    k = pairs.within(s.pos, 0.7)  # comm-range's picks: both directions, padded with -1
    d = torch.cdist(s.pos.detach(), s.pos.detach()) + torch.eye(300, dtype=d.dtype) * 1e9
    for b, i in ((0, 0), (1, 5), (2, 299)):
        assert sorted(k[b, i][k[b, i] >= 0].tolist()) == torch.nonzero(d[b, i] <= 0.7).flatten().tolist()
    assert k.shape[-1] == int((d <= 0.7).sum(-1).max())


@pytest.mark.parametrize("spread", [12.0, 2000.0])  # a span the key table covers, and one it does not
def test_the_compiled_cell_list_gives_the_torch_pairs_in_their_order(spread, monkeypatch):
    """The compiled candidates (the ranges by pair_kernels.cell_ranges, or searchsorted for a wide span) against the
    torch path: the same pairs in the same order, so the ramps are summed alike."""
    if not pairs._numba_on(torch.zeros(1)):
        pytest.skip("numba is not installed (the compiled cell list needs it)")
    s = _scattered(2, 400, spread, dtype=torch.float32)
    grid = torch.stack(torch.meshgrid(torch.arange(12.0), torch.arange(12.0), indexing="ij"), -1).reshape(1, -1, 2)
    for pos, radius in ((s.pos, 0.7), (grid, 1.0)):  # on the grid, pairs exactly at the radius
        for inclusive in (False, True):
            got = {}
            for compiled, loops in ((True, True), (True, False), (False, True)):  # exact kernel, candidates, torch
                monkeypatch.setattr(pairs, "_numba_on", lambda pos, c=compiled: c)
                monkeypatch.setattr(pairs, "COMPILED_LOOPS", loops)
                got[compiled, loops] = pairs.close_pairs(pos, radius, inclusive)
            ref = got[False, True]
            for f, sec in got.values():
                assert torch.equal(f, ref[0]) and torch.equal(sec, ref[1])
            if pos is grid:  # 2 x 12 x 11 neighbours exactly 1 apart: kept only by <=
                assert ref[0].numel() == (264 if inclusive else 0)
            else:
                assert ref[0].numel() > 0


@pytest.fixture
def one_thread():
    """torch at one thread (the default `threads=1`): the order the compiled ramps' backward reproduces."""
    was = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(was)


def test_the_compiled_ramps_are_the_torch_ramps_and_gradients_bit_for_bit(monkeypatch, one_thread):
    """near_ramps by its kernels (sums in index_add's order, the backward in autograd's arithmetic) against its torch
    ops, in float32, on a crowded swarm with coincident agents: the sums and the positions' gradient equal bit for
    bit at one thread."""
    if not pairs._numba_on(torch.zeros(1)):
        pytest.skip("numba is not installed (the compiled ramps need it)")
    s = _scattered(3, 500, 9.0, dtype=torch.float32)
    s = dataclasses.replace(s, pos=torch.cat([s.pos.detach()[:, :490], s.pos.detach()[:, :10]], 1))  # coincident
    env = _cross(0)
    w = torch.randn(3, generator=torch.Generator().manual_seed(1))
    got = {}
    for ramps in (True, False):
        monkeypatch.setattr(pairs, "COMPILED_RAMPS", ramps)
        pos = s.pos.detach().clone().requires_grad_()
        cost = env.collision_cost(dataclasses.replace(s, pos=pos))
        assert (type(cost.grad_fn).__name__ == "NearRampsBackward") == ramps  # the kernels ran, or the torch ops
        grad, = torch.autograd.grad((cost * w).sum(), pos)
        got[ramps] = cost.detach(), grad
    assert got[True][0].min() > 0 and (got[True][1] != 0).float().mean() > 0.5
    assert torch.equal(got[True][0], got[False][0]) and torch.equal(got[True][1], got[False][1])


def test_a_nan_in_a_ramp_is_a_nan_in_its_sum_on_both_paths(monkeypatch):
    """A NaN weight (a task with collision_weight = 0 and collision_dist = 0: slope 0 / 0) reaches the sum as
    through torch's relu, never dropped."""
    if not pairs._numba_on(torch.zeros(1)):
        pytest.skip("numba is not installed (the compiled ramps need it)")
    flat = torch.tensor([[0.0, 0.0], [0.5, 0.0], [3.0, 0.0], [3.2, 0.0]])
    first, second, same = torch.tensor([0, 2]), torch.tensor([1, 3]), torch.tensor([True, False])
    weight, slope = torch.tensor([5.0, 0.0]), torch.tensor([5.0, float("nan")])
    for ramps in (True, False):
        monkeypatch.setattr(pairs, "COMPILED_RAMPS", ramps)
        out = pairs.near_ramps(flat, first, second, same, weight, slope, 2, 2)
        assert out[0] == 7.5 and out[1].isnan()


@pytest.mark.parametrize("n, spread", [(40, 3.0), (300, 25.0)])
def test_cell_list_collision_cost_equals_the_dense_ramp_and_its_gradient(n, spread):
    """In float64, so the only difference, the order of the sum, is far below the tolerance."""
    s = _scattered(2, n, spread)
    dense, sparse = _cross(10 ** 9), _cross(0)
    cd, cs = dense.collision_cost(s), sparse.collision_cost(s)
    assert cd.abs().min() > 0 and torch.allclose(cd, cs, rtol=1e-12, atol=0)
    gd, = torch.autograd.grad(cd.sum(), s.pos)
    gs, = torch.autograd.grad(cs.sum(), s.pos)
    assert gd.abs().max() > 0 and torch.allclose(gd, gs, rtol=1e-10, atol=1e-10)
    assert torch.equal(dense.metrics(s)["collisions"], sparse.metrics(s)["collisions"])
    assert dense.metrics(s)["collisions"].sum() > 0


def test_the_cell_list_is_used_from_sparse_from_agents_on(monkeypatch):
    s = _scattered(1, 50, 4.0, dtype=torch.float32)
    calls = []
    orig = pairs.close_pairs
    monkeypatch.setattr(pairs, "close_pairs", lambda *a, **k: calls.append(1) or orig(*a, **k))
    _cross(51).collision_cost(s)
    assert not calls  # 50 < 51: dense
    _cross(50).collision_cost(s)
    assert calls  # 50 >= 50: the cell list


def test_counter_noise_is_deterministic_normal_and_the_same_however_it_is_read():
    g = torch.Generator().manual_seed(0)
    pos = torch.rand(2, 500, 2, generator=g) * 30
    key = torch.randint(0, 2 ** 62, (2,), generator=g)
    o = pairs.Offsets(pos, 1.0, key)
    full = o.dense()
    assert full.shape == (2, 500, 500, 2) and torch.equal(full, o.dense())
    eps = (full - (pos[:, None] - pos[:, :, None])).reshape(-1, 2)
    assert abs(float(eps.mean())) < 0.01 and abs(float(eps.std()) - 1.0) < 0.01
    assert abs(float((eps[:, 0] * eps[:, 1]).mean())) < 0.01  # the two components independent
    recv = torch.tensor([[3, 499, 0]] * 2)
    send = torch.tensor([[7, 0, 250]] * 2)
    got = o.at(recv, send)
    assert torch.allclose(got, full[torch.arange(2)[:, None], recv, send], atol=1e-5)
    assert torch.equal(o.rows(100, 130), full[:, 100:130])
    other = pairs.Offsets(pos, 1.0, key + 1)
    assert not torch.allclose(other.rows(0, 5), o.rows(0, 5))


def test_the_compiled_noise_of_given_pairs_is_the_torch_noise_bit_for_bit(monkeypatch):
    """Offsets.at's noise by pair_kernels.noise_at against counter_normal's torch ops; the positions keep their
    gradient either way."""
    if not pairs._numba_on(torch.zeros(1)):
        pytest.skip("numba is not installed (the compiled noise needs it)")
    g = torch.Generator().manual_seed(2)
    pos = (torch.rand(3, 700, 2, generator=g) * 40).requires_grad_()
    o = pairs.Offsets(pos, 0.05, torch.randint(0, 2 ** 62, (3,), generator=g))
    recv = torch.randint(0, 700, (3, 700, 2), generator=g)
    send = torch.randint(0, 700, (3, 700, 2), generator=g)
    got = {}
    for compiled in (True, False):
        monkeypatch.setattr(pairs, "_numba_on", lambda p, c=compiled: c)
        got[compiled] = o.at(recv, send)
    assert got[True].shape == (3, 700, 2, 2) and torch.equal(got[True], got[False])
    grad, = torch.autograd.grad(got[True].sum(), pos)
    assert grad.abs().sum() > 0


PROGRAM = "argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nargmax(map(1.0*d, filter(d <= 3.0, l)))\n" \
          "argmax(map(-1.0*gd + 1.0*dx, filter(dy >= 0.0, l)))"


def _providers(env):
    fmap = env.features("v1")
    return {"prog": ProgramComm(parse(PROGRAM), fmap), "dist": NearestComm(3), "no-comm": NoComm()}


@pytest.mark.parametrize("name", ["prog", "dist", "no-comm"])
def test_sparse_and_dense_paths_give_the_same_picks_actions_and_weights(name):
    """One observation, as a pair source (sparse path) and as its dense tensor (dense path): the same picks, the
    same actions, weights and degrees, exactly (the same arithmetic on the same pairs)."""
    env = _cross(0)
    state = env.reset(3, torch.Generator().manual_seed(0))[0]
    torch.manual_seed(0)
    policy = CommTransformer.for_task(env, ModelConfig(dropout=0.0))
    comm = _providers(env)[name]
    rng = Rng(torch.Generator().manual_seed(1))
    obs = env.observe(state, rng)
    assert obs.pairs is not None and obs.rel_shape == (3, 40, 40, 2)
    dense = Observation(obs.agent, obs.pairs.dense())
    outs = []
    for o in (obs, dense):
        ctx = CommContext(env, state, o, rng)
        outs.append(policy(o, lambda lg, r: comm.select(ctx, lg, r), lambda r: comm.picks(ctx, r)))
    sparse_out, dense_out = outs
    assert isinstance(sparse_out.heard[0], Heard) and not isinstance(dense_out.heard[0], Heard)
    assert torch.equal(sparse_out.action, dense_out.action)
    assert torch.equal(sparse_out.masks[0], dense_out.masks[0])
    assert torch.equal(sparse_out.attn[0], dense_out.attn[0])
    assert all(torch.equal(a, b) for a, b in zip(degree_stats([sparse_out.heard[0]]),
                                                   degree_stats([dense_out.masks[0]])))


def test_sparse_rollout_matches_the_dense_one_within_float_rounding():
    """Whole rollouts of a small team: the sparse path (pair source, cell-list ramps) against the dense one fed the
    same noise: costs and degrees agree to float32 rounding (the collision sum runs in another order), picks
    exactly (checked step by step through the degrees)."""
    sparse_env = _cross(0)
    dense_env = _cross(10 ** 9)
    seen = {}

    class SameNoise(RandomCrossTask):  # dense tensors, with the sparse path's counter-based noise
        def observe(self, state, rng):
            o = sparse_env.observe(state, rng)
            return Observation(o.agent, o.pairs.dense())

    same = SameNoise(dense_env.cfg)
    state = sparse_env.reset(2, torch.Generator().manual_seed(0))[0]
    torch.manual_seed(0)
    policy = CommTransformer.for_task(sparse_env, ModelConfig(dropout=0.0))
    for name, comm in _providers(sparse_env).items():
        for label, env in (("sparse", sparse_env), ("dense", same)):
            with torch.no_grad():
                seen[label] = rollout(env, policy, comm, state, Rng(torch.Generator().manual_seed(5)), 12)
        s, d = seen["sparse"], seen["dense"]
        assert torch.allclose(s.cost, d.cost, rtol=1e-5), name
        for k in ("max_in", "max_out", "mean_degree"):
            assert torch.equal(getattr(s, k), getattr(d, k)), (name, k)
        assert torch.equal(s.task_metrics["collisions"], d.task_metrics["collisions"])


def test_random_rules_and_link_failure_do_not_depend_on_the_chunk_size(monkeypatch):
    env = _cross(0)
    state = env.reset(2, torch.Generator().manual_seed(0))[0]
    comm = LinkFailure(ProgramComm(parse("random(filter(d >= 1.0, l))\nargmax(map(-1.0*d, filter(d >= 0.0, l)))"),
                                   env.features("v1")), 0.3)

    def picks():
        rng = Rng(torch.Generator().manual_seed(3))
        obs = env.observe(state, rng)
        return comm.picks(CommContext(env, state, obs, rng), 0)

    whole = picks()
    monkeypatch.setattr(pairs, "PAIR_CHUNK", 2 * 40 * 3)  # three receivers a chunk
    monkeypatch.setattr("neurosym_cli.policy.scan.rows_per_chunk", lambda b, n: 3)
    chunked = picks()
    assert torch.equal(whole, chunked)
    assert (whole[..., 0] >= 0).any() and (whole == -1).any()  # random picks made, some links failed
    d = state.pos[:, :, None].sub(state.pos[:, None]).norm(dim=-1)
    ok = whole[..., 0] >= 0
    assert (d.gather(2, whole[..., :1].clamp(min=0))[..., 0][ok] >= 1.0 - 0.3).all()  # noisy filter d >= 1


def test_the_compiled_rows_are_the_torch_rows_bit_for_bit(monkeypatch):
    from neurosym_cli.tasks import pair_kernels

    if not pair_kernels.AVAILABLE:
        pytest.skip("numba is not installed")
    g = torch.Generator().manual_seed(2)
    pos = torch.rand(2, 301, 2, generator=g) * 40 - 20
    key = torch.randint(0, 2 ** 62, (2,), generator=g)
    o = pairs.Offsets(pos, 0.05, key)
    compiled = o.rows(10, 200)
    uniforms = pairs.uniform_rows(key, 10, 200, 301)
    monkeypatch.setattr(pair_kernels, "AVAILABLE", False)
    assert torch.equal(compiled, o.rows(10, 200))
    assert torch.equal(uniforms, pairs.uniform_rows(key, 10, 200, 301))
    # the int32 hash wraps as the same hash in int64 arithmetic would (what the kernel's uint32 code computes)
    x = torch.randint(-2 ** 31, 2 ** 31, (10000,), generator=g, dtype=torch.int64)
    m = 0xFFFFFFFF

    def mix64(v):
        v = v ^ (v >> 16)
        v = (v * 0x7FEB352D) & m
        v = v ^ (v >> 15)
        v = (v * 0x5BD1E995) & m
        return v ^ (v >> 16)

    assert torch.equal(pairs._mix32(x.to(torch.int32)).to(torch.int64) & m, mix64(x & m))
