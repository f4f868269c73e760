"""The fused filter scan of large teams (policy/scan.py, policy/scan_kernels.py): the same picks as the reference
scan, bit for bit, for every filter shape, score, feature kind and noise setting, close calls on the angle included."""

import dataclasses
import math

import numpy as np
import pytest
import torch

from neurosym_cli.dsl import ast
from neurosym_cli.dsl.parser import parse
from neurosym_cli.policy import scan, scan_kernels
from neurosym_cli.policy.comm import CommContext, ProgramComm
from neurosym_cli.tasks.base import Rng
from neurosym_cli.tasks.random_cross import CrossConfig, RandomCrossTask

pytestmark = pytest.mark.skipif(not scan_kernels.AVAILABLE, reason="numba is not installed (the fused scan needs it)")

PROGRAMS = {
    "v1": [
        "argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nrandom(filter(d >= 3.6, l))",
        "argmax(map(-1.0*gd + 1.0*dx, filter(dy >= 0.0 and gtheta >= 0.3, l)))\n"
        "argmax(map(1.0*d, filter(d <= 3.0 or theta >= 2.0, l)))\nrandom(filter(true, l))",
        "argmax(map(1.0*theta, filter(true, l)))\nargmax(map(-1.0*theta + 0.5*d, filter(-1.0*dx >= 0.5, l)))",
        "random(filter((theta >= 0.5 and d <= 2.0) or (gd >= 1.0 and dy <= -0.2), l))\n"
        "argmax(map(1.0*gx, filter(d >= 1000.0, l)))",  # a filter that passes nobody, a score that ties
        "argmax(map(1.0*gd - 2.0*theta, filter(gd + theta >= 0.7, l)))\nargmax(map(-1.0*dy, filter(gd >= 1e9, l)))",
        # random rules over filters that pass few (the cell scan's winners struck out until it reads every cell)
        "random(filter(d <= 1.5 and theta >= 1.0, l))\nrandom(filter(-1.0*d >= -0.8, l))",
    ],
    "v2": [
        "argmax(map(1.0*gx_dx, filter(gy_dy >= 0.5, l)))\nrandom(filter(gd >= 3.0, l))",
        "argmax(map(1.0*gx_dy - 1.0*gy_dx, filter(gx_dx >= -0.5 and theta >= -2.0, l)))",
    ],
}


def _picks(env, program, version, state, seed, fused, monkeypatch):
    monkeypatch.setattr(scan, "FUSED", fused)
    comm = ProgramComm(program, env.features(version))
    rng = Rng([torch.Generator().manual_seed(seed + e) for e in range(state.pos.shape[0])])
    obs = env.observe(state, rng)
    assert obs.pairs is not None  # the sparse path
    return comm.picks(CommContext(env, state, obs, rng), 0)


@pytest.mark.parametrize("cells", [False, True], ids=["every-pair", "by-cells"])
@pytest.mark.parametrize("noise", [0.0, 0.1])
@pytest.mark.parametrize("version", ["v1", "v2"])
def test_the_fused_scan_gives_the_reference_picks_bit_for_bit(version, noise, cells, monkeypatch):
    """Both fused kernels: every pair computed (scan_kernels) and decided by cells (scan_cells, forced on here at
    40 agents, where its cells hold a few agents each)."""
    monkeypatch.setattr(scan, "CELLS_FROM", 0 if cells else 10 ** 9)
    env = RandomCrossTask(CrossConfig(name="random-cross", group_prob=1.0, sparse_from=0, noise_std=noise))
    for seed in range(3):
        state = env.reset(3, torch.Generator().manual_seed(seed))[0]
        for text in PROGRAMS[version]:
            program = parse(text)
            assert scan.compile_round(program, 0, env.features(version)) is not None, text
            fused = _picks(env, program, version, state, 7 + seed, True, monkeypatch)
            ref = _picks(env, program, version, state, 7 + seed, False, monkeypatch)
            assert fused.shape == (3, 40, program.max_rules)
            assert torch.equal(fused, ref), text
            if text.startswith("random(filter((theta"):  # a filter that passes nobody (-1), ties under a constant
                assert (fused[..., 1] == -1).all()
            if text.startswith("random(filter(d <= 1.5"):
                assert (fused >= 0).any() and (fused == -1).any()  # some pass, some pass nobody


def test_the_cell_scan_gives_the_every_pair_picks_on_a_large_swarm(monkeypatch):
    """600 agents in about 50 cells: the cells' bounds decide most pairs, and the picks stay the every-pair kernel's
    (itself the reference's, above), for every program of the suite that the swarm's features serve."""
    from neurosym_cli.tasks.swarm import SwarmConfig, SwarmTask

    env = SwarmTask(SwarmConfig(name="swarm", agents_per_group=300))
    state = env.reset(2, torch.Generator().manual_seed(1))[0]
    for text in PROGRAMS["v1"]:
        program = parse(text)
        got = {}
        for cells in (True, False):
            monkeypatch.setattr(scan, "CELLS_FROM", 0 if cells else 10 ** 9)
            got[cells] = _picks(env, program, "v1", state, 3, True, monkeypatch)
        assert torch.equal(got[True], got[False]), text


def test_a_random_rules_key_orders_candidates_as_the_float32_uniform_and_the_index_do():
    """Above 2^23 the reference's float32 (u24 + 0.5) rounds to even, so u24 = 2k + 1 and 2k + 2 give one uniform and
    the lower index wins: the cell scan's integer key must tie them too (a swarm of 1,000 met this every few
    steps before the key said so)."""
    from neurosym_cli.policy import scan_cells

    def uniform(u24):
        return (np.float32(u24) + np.float32(0.5)) * np.float32(1.0 / (1 << 24))

    for u24 in (5, 6, (1 << 23) - 1, 1 << 23, (1 << 23) + 1, 16742671, 16742672, (1 << 24) - 2, (1 << 24) - 1):
        for other in (o for o in (u24 - 1, u24 + 1) if o < 1 << 24):
            for j, k in ((3, 7), (7, 3)):
                a = scan_cells.uniform_key(np.uint32(u24 << 8 | 0x5A), j)
                b = scan_cells.uniform_key(np.uint32(other << 8), k)
                want = (uniform(u24), -j) > (uniform(other), -k)
                assert (a > b) == want and a > 0, (u24, other, j, k)


@pytest.mark.parametrize("cells", [False, True], ids=["every-pair", "by-cells"])
def test_close_calls_on_the_angle_are_decided_by_the_exact_angle(cells, monkeypatch):
    """Thresholds set to pairs' exact bearings (float32 atan2, as the reference computes them): the fast angle is
    below the threshold for some of them, and the picks still equal the reference's."""
    monkeypatch.setattr(scan, "CELLS_FROM", 0 if cells else 10 ** 9)
    env = RandomCrossTask(CrossConfig(name="random-cross", group_prob=1.0, sparse_from=0, noise_std=0.1))
    state = env.reset(2, torch.Generator().manual_seed(3))[0]
    rng = Rng([torch.Generator().manual_seed(11 + e) for e in range(2)])
    rel = env.observe(state, rng).pairs.dense()
    theta = torch.atan2(rel[..., 1], rel[..., 0])  # strided, as the reference's feature map reads o_ij
    fast_below = 0
    for i, j in [(0, 5), (3, 17), (10, 2), (22, 39), (31, 8), (5, 6), (12, 30), (39, 0)]:
        t = float(theta[0, i, j])
        fast = scan_kernels._atan2_fast(np.float32(rel[0, i, j, 1]), np.float32(rel[0, i, j, 0]))
        fast_below += float(fast) < t
        assert abs(float(fast) - t) < float(scan_kernels.THETA_ERR)
        for rule in (ast.ArgMaxRule(ast.Linear((("d", -1.0),)), ast.Test(ast.Linear((("theta", 1.0),)), t)),
                     ast.ArgMaxRule(ast.Linear((("d", 1.0),)), ast.Test(ast.Linear((("theta", -1.0),)), -t))):
            program = ast.Program(((rule,),))
            fused = _picks(env, program, "v1", state, 11, True, monkeypatch)
            assert torch.equal(fused, _picks(env, program, "v1", state, 11, False, monkeypatch))
    assert fast_below > 0  # the fast angle alone would have decided some of these wrongly


def test_the_fast_angle_is_within_its_bound_signed_zeros_included():
    rng = np.random.default_rng(0)
    x = (rng.standard_normal(200_000) * rng.choice([1e-3, 1.0, 50.0], 200_000)).astype(np.float32)
    y = (rng.standard_normal(200_000) * rng.choice([1e-3, 1.0, 50.0], 200_000)).astype(np.float32)
    x[:8] = [0.0, -0.0, 0.0, -0.0, -1.0, -1.0, 1.0, 0.0]
    y[:8] = [0.0, 0.0, -0.0, -0.0, 0.0, -0.0, -0.0, -2.0]
    fast = np.array([scan_kernels._atan2_fast(a, b) for a, b in zip(y, x)], np.float64)
    exact = np.arctan2(y, x).astype(np.float64)
    assert np.abs(fast - exact).max() < float(scan_kernels.THETA_ERR) / 10
    assert np.array_equal(np.signbit(fast[:8]), np.signbit(exact[:8]))  # atan2(-0, -1) = -pi, atan2(-0, 0) = -0


def test_features_only_the_task_knows_fall_back_to_the_reference_scan(monkeypatch):
    """A pair feature without a Source is not compiled: the reference scan runs it, with the same picks as ever."""
    from neurosym_cli.dsl.vocabulary import Feature
    from neurosym_cli.tasks.features import vector_map

    env = RandomCrossTask(CrossConfig(name="random-cross", group_prob=1.0, sparse_from=0))
    extra = (Feature("dd", "other", "its squared distance", "world units^2", (0.0, math.inf)),
             lambda v: (v.rel[..., :2] ** 2).sum(-1))
    fmap = vector_map([("g", "my goal", lambda v: -v.agent[..., :2])], "v1", extra=[extra])
    program = parse("argmax(map(-1.0*dd, filter(true, l)))")
    assert scan.compile_round(program, 0, fmap) is None
    assert scan.compile_round(parse("argmax(map(-1.0*d, filter(true, l)))"), 0, fmap) is not None
    monkeypatch.setattr(env, "features", lambda version: fmap)
    state = env.reset(2, torch.Generator().manual_seed(0))[0]
    near = _picks(env, program, "v1", state, 1, True, monkeypatch)
    by_d = _picks(env, parse("argmax(map(-1.0*d, filter(true, l)))"), "v1", state, 1, True, monkeypatch)
    assert (near == by_d).float().mean() > 0.95  # the nearest by d^2 is the nearest by d (up to rounding ties)


def test_the_fused_scan_serves_a_swarm_and_its_rollout_equals_the_reference(monkeypatch):
    """A few steps of a 300-agent swarm under a program: the same picks step by step, so the same costs."""
    from neurosym_cli.config import ModelConfig
    from neurosym_cli.policy.transformer import CommTransformer
    from neurosym_cli.rollout import rollout
    from neurosym_cli.tasks.swarm import SwarmConfig, SwarmTask

    env = SwarmTask(SwarmConfig(name="swarm", agents_per_group=150))
    state = env.reset(1, torch.Generator().manual_seed(0))[0]
    torch.manual_seed(0)
    policy = CommTransformer.for_task(env, ModelConfig(dropout=0.0))
    comm = ProgramComm(parse(PROGRAMS["v1"][0]), env.features("v1"))
    out = {}
    for fused in (True, False):
        monkeypatch.setattr(scan, "FUSED", fused)
        with torch.no_grad():
            out[fused] = rollout(env, policy, comm, state, Rng([torch.Generator().manual_seed(5)]), 4)
    assert torch.equal(out[True].cost, out[False].cost)
    assert torch.equal(out[True].max_in, out[False].max_in)


def test_a_compiled_round_lists_each_feature_once_with_products_after_their_factors():
    env = RandomCrossTask(dataclasses.replace(CrossConfig(name="random-cross"), sparse_from=0))
    c = scan.compile_round(parse("argmax(map(1.0*gx_dx + 1.0*dx, filter(theta >= 0.1 and gx >= 0.0, l)))"), 0,
                           env.features("v2"))
    kinds = c.pair["pk"].tolist()
    assert kinds.count(scan_kernels.PRODUCT) == 1 and kinds.count(scan_kernels.X) == 1  # dx shared
    prod = kinds.index(scan_kernels.PRODUCT)
    assert c.pair["pa"][prod] < prod or c.pair["pb"][prod] < prod  # its pair factor comes first
    assert c.agent == ("gx",)  # one agent feature, read by the product and the test


@pytest.mark.parametrize("batch", [1, 3])
def test_the_receivers_shared_among_threads_give_the_same_picks(batch, monkeypatch):
    env = RandomCrossTask(CrossConfig(name="random-cross", group_prob=1.0, sparse_from=0))
    state = env.reset(batch, torch.Generator().manual_seed(4))[0]
    program = parse(PROGRAMS["v1"][1])
    one = _picks(env, program, "v1", state, 2, True, monkeypatch)
    monkeypatch.setattr(scan, "PARALLEL_FROM", 0)
    threads = torch.get_num_threads()
    torch.set_num_threads(3)
    try:
        shared = _picks(env, program, "v1", state, 2, True, monkeypatch)
    finally:
        torch.set_num_threads(threads)
    assert torch.equal(one, shared)


def test_what_the_kernel_cannot_decide_as_the_reference_does_is_left_to_it():
    env = RandomCrossTask(CrossConfig(name="random-cross", group_prob=1.0, sparse_from=0))
    fmap = env.features("v1")
    long_form = " + ".join(f"1.0*{f}" for f in ("dx", "dy", "d", "theta", "gx", "gy", "gd", "gtheta", "gx_dx"))
    assert scan.compile_round(parse(f"argmax(map(-1.0*d, filter({long_form} >= 0.0, l)))"), 0,
                              env.features("v2")) is None  # nine terms
    assert scan.compile_round(parse("argmax(map(1e20*d, filter(true, l)))"), 0, fmap) is None
    assert scan.compile_round(parse("argmax(map(1e9*d, filter(true, l)))"), 0, fmap) is not None


def test_the_retraining_benchmark_runs_both_paths_to_the_same_losses(tmp_path):
    """benchmarks/bench_swarm_retrain.py on a small case: the old path (every pair, searchsorted, torch noise) and the
    new one train the same weights to the same losses, bit for bit."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "r.json"
    cmd = [sys.executable, str(root / "benchmarks/bench_swarm_retrain.py"), "--agents", "300", "--horizon", "3",
           "--steps", "2", "--json", str(out)]
    subprocess.run(cmd, check=True, capture_output=True, cwd=tmp_path)
    row = json.loads(out.read_text())
    assert row["losses_equal"] and len(row["now"]["losses"]) == 2 and row["ratio_cpu"] > 0


def test_a_form_whose_float32_terms_overflow_is_left_to_the_pairs(monkeypatch):
    """3e37 d - 3e37 dx is inf - inf = NaN in float32, so the test fails for those pairs in the every-pair kernel;
    the cells' float64 bounds must not call such a cell true. Such weights are above MAX_WEIGHT, where the reference
    scan runs; lifted here to reach the kernels."""
    env = RandomCrossTask(CrossConfig(name="random-cross", group_prob=1.0, sparse_from=0, noise_std=0.0))
    state = env.reset(1, torch.Generator().manual_seed(0))[0]
    texts = ["random(filter(3e37*d - 3e37*dx >= -3e38, l))",
             "argmax(map(1.0*d, filter(3e37*d - 3e37*dx >= -3e38, l)))"]
    assert all(scan.compile_round(parse(t), 0, env.features("v1")) is None for t in texts)  # the reference's
    monkeypatch.setattr(scan, "MAX_WEIGHT", 1e38)
    scan._compile.cache_clear()
    try:
        for text in texts:
            program = parse(text)
            assert scan.compile_round(program, 0, env.features("v1")) is not None
            got = {}
            for cells in (True, False):
                monkeypatch.setattr(scan, "CELLS_FROM", 0 if cells else 10 ** 9)
                got[cells] = _picks(env, program, "v1", state, 7, True, monkeypatch)
            assert torch.equal(got[True], got[False]), text
    finally:
        scan._compile.cache_clear()
