"""The rl baseline (paper appendix D): communication decisions as actions, trained by policy gradient."""

import json
from types import SimpleNamespace

import pytest
import torch

from test_cli import run


def _gate_and_inputs(b, n=4, seed=0):
    from neurosym_cli.tasks.base import Rng
    from neurosym_cli.policy.gated import GatedComm

    torch.manual_seed(seed)
    gate = GatedComm(rounds=1)
    with torch.no_grad():  # a gate that is not at its initial point, so every parameter matters
        for p in gate.parameters():
            p.add_(0.5 * torch.randn_like(p))
    logits = torch.randn(1, n, n).expand(b, n, n)  # every episode in the same state: (B, N, N)
    rel = torch.randn(1, n, n, 2).expand(b, n, n, 2)
    ctx = SimpleNamespace(obs=SimpleNamespace(rel=rel), rng=Rng(torch.Generator().manual_seed(seed + 1)))
    return gate, logits, rel, ctx


@pytest.mark.parametrize("shaped", [True, False])
def test_score_function_estimate_matches_the_exact_gradient(shaped):
    """Two steps, each with its own decisions and a cost linear in them: E[cost] = sum_t sum_ij c_tij p_ij, so its
    exact gradient is known. The mean of the estimator over many episodes must match it, with the reward to go and
    with the whole episode's return (both unbiased), the leave-one-out baseline included."""
    from neurosym_cli.policy.gated import score_function_loss

    b, n = 40000, 4
    gate, logits, rel, ctx = _gate_and_inputs(b, n)
    c = torch.randn(2, n, n)  # (T, N, N) cost of hearing j at each step
    costs, logps, degs = [], [], []
    for t in range(2):
        mask = gate.select(ctx, logits, 0)
        logp, deg = gate.pop_step()
        costs.append((mask.float() * c[t]).sum((1, 2)))
        logps.append(logp)
        degs.append(deg)
    surrogate = score_function_loss(torch.stack(costs), torch.stack(degs), torch.stack(logps), torch.ones(2), 0.0,
                                    shaped) / b
    est = torch.autograd.grad(surrogate, list(gate.parameters()))
    p = torch.sigmoid(gate.gate_logits(logits[:1], rel[:1], 0))[0]  # (N, N)
    off = ~torch.eye(n, dtype=torch.bool)
    exact = torch.autograd.grad((c.sum(0) * p * off).sum(), list(gate.parameters()))
    flat_est, flat_exact = torch.cat([g.flatten() for g in est]), torch.cat([g.flatten() for g in exact])
    err = (flat_est - flat_exact).norm() / flat_exact.norm()
    assert err < 0.1, (err, flat_est[:4], flat_exact[:4])
    # without the baseline's help the estimate is not degenerate: it points the same way
    assert torch.dot(flat_est, flat_exact) > 0


def test_degree_is_charged_and_no_decisions_are_recorded_without_gradients():
    from neurosym_cli.policy.gated import GatedComm, score_function_loss

    gate, logits, rel, ctx = _gate_and_inputs(8)
    with torch.no_grad():
        gate.select(ctx, logits, 0)
    assert gate.pop_step() is None  # evaluation: nothing kept
    mask = gate.select(ctx, logits, 0)
    logp, deg = gate.pop_step()
    m = mask.float()
    assert torch.equal(deg, (m.sum(2) + m.sum(1)).amax(1))
    assert not mask.diagonal(dim1=1, dim2=2).any()  # nobody hears itself
    # the degree enters the advantage with its weight: more cost per degree, a larger push down on the bias
    zero = torch.zeros(1, 8)
    g0 = torch.autograd.grad(score_function_loss(zero, deg[None], logp[None], torch.ones(1), 0.0, True),
                             gate.bias, retain_graph=True, allow_unused=True)[0]
    g1 = torch.autograd.grad(score_function_loss(zero, deg[None], logp[None], torch.ones(1), 1.0, True), gate.bias)[0]
    assert g0 is None or torch.count_nonzero(g0) == 0
    assert torch.count_nonzero(g1) > 0
    assert isinstance(GatedComm(2).picks(ctx, 0), type(None))


def test_the_score_function_term_trains_the_gate_alone():
    """The gate reads the transformer's logits and the observations through a stop-gradient: the decisions' term
    reaches no weight of the transformer, only the gate's (docs/fidelity.md, the bias taken for variance)."""
    from neurosym_cli.policy.gated import score_function_loss

    gate, logits, rel, ctx = _gate_and_inputs(16)
    logits, rel = logits.clone().requires_grad_(), rel.clone().requires_grad_()
    ctx.obs.rel = rel
    gate.select(ctx, logits, 0)
    logp, deg = gate.pop_step()
    loss = score_function_loss(torch.randn(1, 16), deg[None], logp[None], torch.ones(1), 1.0, True)
    loss.backward()
    assert logits.grad is None and rel.grad is None
    assert gate.bias.grad is not None and torch.count_nonzero(gate.bias.grad) > 0


def _degree(tmp_path, cost):
    # 8 episodes per bucket, so the leave-one-out baseline acts (one-episode buckets fall back to a running mean,
    # far noisier: the degree then wanders whatever the cost)
    run(["train", "task=two-groups-cross", "budget=tiny", "baseline=rl", f"rl.cost={cost}", "rl.lr_scale=100",
         "budget.retrain_rollouts=96", "budget.batch_rollouts=8", "optim.min_steps_per_batch=1"], tmp_path)
    run(["eval", "task=two-groups-cross", "budget=tiny", "baseline=rl", f"rl.cost={cost}"], tmp_path)
    m = json.loads((tmp_path / f"two-groups-cross/tiny/seed0/eval/rl-c{cost}-togo-oracle/metrics.json").read_text())
    return m["summary"]["max_degree"]["mean"]


def test_rl_trains_on_a_tiny_budget_and_its_degree_falls_as_the_cost_rises(tmp_path):
    run(["train", "task=two-groups-cross", "budget=tiny"], tmp_path)
    free, dear = _degree(tmp_path, 0), _degree(tmp_path, 100)
    # measured over 2 seeds x 1-2 threads: free 17-25, dear 0-3.6
    assert dear < 0.5 * free, (free, dear)
    ckpt = torch.load(tmp_path / "two-groups-cross/tiny/seed0/train/rl-c100-togo-oracle/model.pt", weights_only=True)
    assert set(ckpt["comm_state"]) >= {"scale", "bias"}  # the gate travels with the checkpoint
    hist = (tmp_path / "two-groups-cross/tiny/seed0/train/rl-c100-togo-oracle/history.csv").read_text()
    assert "degree" in hist.splitlines()[0]


def test_rl_needs_the_oracle_and_names_the_command(tmp_path):
    p = run(["train", "task=two-groups-cross", "budget=tiny", "baseline=rl"], tmp_path, check=False)
    assert p.returncode != 0 and "Traceback" not in p.stderr
    assert "neurosym train task=two-groups-cross baseline=tf-full" in p.stderr + p.stdout


def test_rl_command_trains_the_grid_picks_rl1_rl2_by_validation_then_tests_them(tmp_path):
    run(["train", "task=two-groups-cross", "budget=tiny"], tmp_path)
    p = run(["rl", "task=two-groups-cross", "budget=tiny", "rl.grid_cost=[0,30]", "rl.grid_shaped=[true]",
             "rl.lr_scale=300", "budget.retrain_rollouts=24", "rl.jobs=1"], tmp_path)
    exp = tmp_path / "two-groups-cross/tiny/seed0"
    grid = json.loads((exp / "rl/grid.json").read_text())
    rows = {r["name"]: r for r in grid["settings"]}
    assert set(rows) == {"rl-c0-togo-oracle", "rl-c30-togo-oracle"}
    picks = json.loads((exp / "rl/picks.json").read_text())
    assert picks["rl1"]["name"] == min(rows.values(), key=lambda r: r["val_loss"])["name"]
    assert picks["rl2"]["name"] == min(rows.values(), key=lambda r: r["max_degree"])["name"]
    for label in ("rl1", "rl2"):
        m = json.loads((exp / "eval" / label / "metrics.json").read_text())
        assert m["label"] == label and m["baseline"] == "rl" and m["seeds"] == 2
        # the picks were fixed before any test episode was played
        assert (exp / "rl/picks.json").stat().st_mtime <= (exp / "eval" / label / "metrics.json").stat().st_mtime
    assert "rl1" in p.stdout and "rl2" in p.stdout
    report = run(["report", "task=two-groups-cross", "budget=tiny"], tmp_path)
    assert "rl1" in report.stdout and "rl2" in report.stdout  # in the same table as every other baseline


def test_rl_bad_settings_are_one_line(tmp_path):
    for bad in ("rl.init=teacher", "rl.grid_cost=[-1]", "rl.lr_scale=0"):
        p = run(["rl", "task=two-groups-cross", "budget=tiny", bad], tmp_path, check=False)
        assert p.returncode != 0 and "Traceback" not in p.stderr, bad
        assert "rl." in p.stderr, (bad, p.stderr)


def test_one_episode_buckets_use_the_running_mean_return_as_baseline():
    from neurosym_cli.policy.gated import returns, score_function_loss

    cost, deg, logp = torch.rand(3, 1), torch.rand(3, 1), torch.randn(3, 1)
    ret = returns(cost, deg, torch.ones(3), 2.0, True)  # (T, 1): reward to go
    assert torch.allclose(ret[:, 0], (cost + 2.0 * deg).flip(0).cumsum(0).flip(0)[:, 0])
    fallback = torch.tensor([5.0, 3.0, 1.0])
    got = score_function_loss(cost, deg, logp, torch.ones(3), 2.0, True, fallback)
    assert torch.allclose(got, ((ret[:, 0] - fallback) * logp[:, 0]).sum())
    assert torch.allclose(score_function_loss(cost, deg, logp, torch.ones(3), 2.0, True), (ret * logp).sum())
