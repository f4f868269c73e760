"""Link failure (every baseline, training and evaluation) and the zero-shot stress command."""

import json

import torch

from conftest import PAPER_METHOD
from test_cli import run


def _ctx(b=64, seed=0):
    """A random-grid bucket: b episodes of 3 groups of 4 agents (every episode has N = 12)."""
    from neurosym_cli.tasks.random_grid import GridConfig
    from neurosym_cli.tasks import make_task
    from neurosym_cli.tasks.base import Rng
    from neurosym_cli.policy.comm import CommContext

    env = make_task(GridConfig(name="random-grid", agents_per_group=4), 5)
    g = torch.Generator().manual_seed(seed)
    (state,) = env.reset(b, g)
    rng = Rng(g)
    return env, CommContext(env, state, env.observe(state, rng), rng)


def test_observed_failure_rate_matches_the_setting():
    from neurosym_cli.policy.comm import FullComm, LinkFailure

    env, ctx = _ctx()
    b, n = ctx.obs.agent.shape[:2]
    logits = torch.zeros(b, n, n)
    full = FullComm().select(ctx, logits, 0)
    for p in (0.1, 0.5):
        kept = LinkFailure(FullComm(), p).select(ctx, logits, 0)
        assert not (kept & ~full).any()  # a failure only removes links
        rate = 1 - kept.sum().item() / full.sum().item()
        assert abs(rate - p) < 0.02, (p, rate)  # ~9,000 links: the rate is within 2 points of the setting


def test_picks_lose_failed_messages_and_degrees_count_what_was_delivered():
    from neurosym_cli.dsl.interpret import picks_to_mask
    from neurosym_cli.policy.comm import LinkFailure, NearestComm

    env, ctx = _ctx()
    torch.manual_seed(0)
    inner = NearestComm(3)
    chosen = inner.picks(ctx, 0)
    lf = LinkFailure(inner, 0.5)
    got = lf.picks(ctx, 0)
    lost = got == -1
    assert ((got == chosen) | lost).all()  # a pick is delivered as chosen, or lost; never replaced
    assert 0.4 < lost.float().mean().item() < 0.6
    heard = picks_to_mask(got, chosen.shape[1]).sum(-1)  # in-degree: messages actually delivered
    assert heard.max() <= 3 and abs(heard.float().mean().item() - 1.5) < 0.15


def test_failure_zero_is_the_same_provider_and_the_same_numbers():
    from neurosym_cli.config import ModelConfig
    from neurosym_cli.tasks.random_cross import CrossConfig
    from neurosym_cli.tasks import make_task
    from neurosym_cli.evaluation import evaluate
    from neurosym_cli.policy import CommTransformer
    from neurosym_cli.policy.comm import FullComm, NearestComm, with_link_failure

    c = NearestComm(2)
    assert with_link_failure(c, 0.0) is c  # no wrapper: no extra random draws, results bit-identical
    env = make_task(CrossConfig(name="random-cross", agents_per_group=3), 6)
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig())
    a = evaluate(env, pol, FullComm(), [0, 1], torch.device("cpu"))
    b = evaluate(env, pol, with_link_failure(FullComm(), 0.0), [0, 1], torch.device("cpu"))
    f = evaluate(env, pol, with_link_failure(FullComm(), 0.5), [0, 1], torch.device("cpu"))
    assert a == b
    assert all(x["mean_degree"] < y["mean_degree"] for x, y in zip(f, a))  # half the links lost


def test_link_failure_runs_live_apart_and_train_with_failures(tmp_path):
    p = run(["train", "task=random-grid", "budget=tiny", "task.link_failure=0.5", "threads=1"], tmp_path)
    assert (tmp_path / "random-grid-fail0.5/tiny/seed0/train/oracle/model.pt").exists(), p.stdout
    assert not (tmp_path / "random-grid").exists()
    p = run(["train", "task=random-grid", "task.link_failure=1.0"], tmp_path, check=False)
    assert p.returncode == 2 and "task.link_failure must lie in [0, 1)" in p.stderr  # a config error (errors.EXIT_CONFIG)


def test_stress_command_on_a_tiny_run(tmp_path):
    # the paper's method (PAPER_METHOD): stress's prog-retrained is the searched program's retraining, which a
    # pipeline under pipeline.select=front (the front's pick) does not make
    run(["pipeline", "task=two-groups-cross", "budget=tiny", "threads=1", "rules=1",
         "baselines=[tf-full,prog,prog-retrained]", *PAPER_METHOD], tmp_path)
    p = run(["stress", "task=two-groups-cross", "budget=tiny", "threads=1", "rules=1", *PAPER_METHOD,
             "stress.agents=[3,20]", "stress.failure=[0,0.5]", "stress.seeds=2",
             "stress.baselines=[tf-full,prog-retrained,dist]"], tmp_path, plots=True)
    out = tmp_path / "two-groups-cross/tiny/seed0/stress"
    res = json.loads((out / "stress.json").read_text())
    assert (out / "stress.png").exists() and (out / "stress.csv").exists()
    assert "dist-k1" in res["skipped"] and "neurosym train" in res["skipped"]["dist-k1"]
    prog = [r for r in res["results"] if r["baseline"] == "prog-retrained"]
    assert {(r["max_agents"], r["link_failure"]) for r in prog} == {(6, 0.0), (40, 0.0), (20, 0.0), (20, 0.5)}
    assert all(r["max_in"]["mean"] <= 1.0 + 1e-6 for r in prog)  # K = 1 at N = 40: in-degree bounded by construction
    full = {(r["max_agents"], r["link_failure"]): r for r in res["results"] if r["baseline"] == "tf-full"}
    assert full[(40, 0.0)]["max_in"]["mean"] > full[(6, 0.0)]["max_in"]["mean"]
    assert full[(20, 0.5)]["mean_degree"]["mean"] < full[(20, 0.0)]["mean_degree"]["mean"]
    assert "zero-shot link failure" in p.stdout
