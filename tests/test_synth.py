"""Synthesis: cached incremental scoring equals a full forward pass; MCMC recovers a planted program."""

import random
from pathlib import Path

import pytest
import torch

from neurosym_cli.config import ModelConfig
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.tasks.unlabeled_goals import UnlabeledConfig
from neurosym_cli.dsl import ArgMaxRule, Linear, Program, RandomRule, TrueCond
from neurosym_cli.dsl.interpret import picks_to_mask, rule_picks
from neurosym_cli.dsl.sampling import SearchSpace, propose, random_rules
from neurosym_cli.tasks import Observation, make_task
from neurosym_cli.policy import CommTransformer
from neurosym_cli.synth.dataset import DataBucket, collect
from neurosym_cli.synth.mcmc import metropolis, phases
from neurosym_cli.synth.objective import CachedScorer
from neurosym_cli.synth.search import feature_quantiles

CPU = torch.device("cpu")
ROOT = Path(__file__).resolve().parents[1]


def _setup(task=None, rounds=1, rollouts=6):
    task = task or CrossConfig(name="random-cross", horizon=12)
    env = make_task(task)
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, rounds, ModelConfig()).eval()
    data = collect(env, pol, rollouts, 2, torch.Generator().manual_seed(0), CPU)
    return env, pol, data


def _walk_matches_full_forward(sc, space, rng, rules, steps=10):
    """Accept `steps` proposals in a row; each incremental score equals the full forward pass."""
    sc.score(rules)
    sc.accept()
    for _ in range(steps):
        rules, _ = propose(rules, space, rng)
        inc = sc.score(rules)
        sc.accept()
        full = sc.full_score(Program((rules,)))
        assert abs(inc.total - full.total) <= 1e-4 * max(1.0, full.total)


def _space(scorer, k, det=False):
    return SearchSpace(feature_quantiles(scorer, torch.Generator().manual_seed(0)), k, 2, det)


def test_dataset_shapes():
    env, pol, data = _setup()
    assert sum(b.states for b in data) == 6 * 6  # 6 rollouts x 12 steps / stride 2
    for b in data:
        assert b.rel.shape == (b.states, b.n_agents, b.n_agents, 2) and b.target.shape == (b.states, b.n_agents, 2)
        assert (b.target.norm(dim=-1) <= 2.0 + 1e-4).all()  # the effective (speed-clipped) action


def test_incremental_scoring_equals_full_scoring():
    env, pol, data = _setup()
    sc = CachedScorer(pol, env, data, round_idx=0, version="v2", lam=0.5, objective="paper", cap=3, samples=2,
                      gen=torch.Generator().manual_seed(1), device=CPU)
    space = _space(sc, 3)
    rng = random.Random(0)
    rules = random_rules(space, rng)
    sc.score(rules)
    sc.accept()
    for _ in range(40):
        cand, _ = propose(rules, space, rng)
        inc = sc.score(cand)
        full = sc.full_score(Program((cand,)))
        assert abs(inc.l1 - full.l1) <= 1e-4 * max(1.0, full.l1)
        assert abs(inc.degree - full.degree) <= 1e-6
        if rng.random() < 0.5:
            sc.accept()
            rules = cand
    assert sc.rows_recomputed > 0


def test_random_rules_at_different_positions_are_independent():
    """Two copies of `random(filter(true, l))` pick independently, as at run time: in-degree 2 where the draws
    differ (shared random numbers would make the second copy a duplicate and the in-degree always 1)."""
    env, pol, data = _setup()
    sc = CachedScorer(pol, env, data, round_idx=0, version="v1", lam=0.5, objective="paper", cap=2, samples=1,
                      gen=torch.Generator().manual_seed(1), device=CPU)
    rule = RandomRule(TrueCond())
    a, b = sc.picks_of(rule, 0), sc.picks_of(rule, 1)
    same = sum(int((x == y).sum()) for x, y in zip(a, b))
    total = sum(x.numel() for x in a)
    n_mean = sum(d.n * d.s for d in sc.data) / sc.total_states
    assert same < 0.2 * total  # about 1 / (N - 1) of the rows agree by chance
    assert sc.picks_of(rule, 0) is a  # cached per (rule, position)
    inc = sc.score((rule, rule))
    full = sc.full_score(Program(((rule, rule),)))
    assert abs(inc.total - full.total) <= 1e-4 * max(1.0, full.total) and n_mean > 2


def test_incremental_scoring_two_rounds():
    task = UnlabeledConfig(name="u", horizon=6, rounds=2, agents_per_group=5)
    env, pol, data = _setup(task, rounds=2, rollouts=3)
    for r in (0, 1):
        sc = CachedScorer(pol, env, data, round_idx=r, version="v1", lam=0.7, objective="hinge", cap=2, samples=1,
                          gen=torch.Generator().manual_seed(1), device=CPU)
        space = _space(sc, 2)
        rng = random.Random(r)
        _walk_matches_full_forward(sc, space, rng, random_rules(space, rng))


def test_mcmc_recovers_a_planted_program():
    """Targets made by the transformer under a planted program: the planted program scores L1 = 0."""
    env, pol, data = _setup(rollouts=4)
    planted = (ArgMaxRule(Linear((("d", -1.0),)), TrueCond()),)  # hear the nearest agent
    planted_data = []
    for b in data:
        obs = Observation(b.agent, b.rel)
        from fixtures import feature_map

        feats = feature_map("formation").view(b.agent, b.rel)
        with torch.no_grad():
            out = pol(obs, lambda logits, r: picks_to_mask(rule_picks(planted[0], feats, None)[..., None], b.n_agents))
        planted_data.append(DataBucket(b.agent, b.rel, env.target(out.action)))
    sc = CachedScorer(pol, env, planted_data, round_idx=0, version="v1", lam=0.0, objective="paper", cap=1, samples=1,
                      gen=torch.Generator().manual_seed(0), device=CPU)
    assert sc.score(planted).l1 < 1e-5
    space = _space(sc, 1, det=True)
    rng = random.Random(3)
    res = metropolis(lambda: random_rules(space, rng), lambda r: propose(r, space, rng), sc, steps=400, restarts=2,
                     final_fraction=0.3, temperature=0.1, rng=rng)
    assert res.best_score.l1 < 1e-3, res.best
    got = torch.cat([p.flatten() for p in sc.picks_of(res.best[0])])
    want = torch.cat([p.flatten() for p in sc.picks_of(planted[0])])
    assert (got == want).float().mean() > 0.99


def test_phases_split_the_budget():
    assert phases(10_000, 4, 0.2) == [("restart1", 2000), ("restart2", 2000), ("restart3", 2000),
                                      ("restart4", 2000), ("final", 2000)]
    assert sum(n for _, n in phases(31, 3, 0.25)) == 31
    assert phases(50, 0, 0.2) == [("chain", 50)]


def test_greedy_hard_attention_respects_the_degree_cap():
    from neurosym_cli.synth.tree import greedy_hard_attention

    g = torch.Generator().manual_seed(0)
    attn = torch.softmax(torch.randn(50, 7, 7, generator=g), -1)
    for k in (1, 2, 3):
        take = greedy_hard_attention(attn, k)
        assert (take.sum(2) <= k).all() and (take.sum(1) <= k).all()
        assert not take.diagonal(dim1=1, dim2=2).any()
        assert (take.sum((1, 2)) >= k).all()  # it does take edges
    # the strongest pair is always taken; a pair that would exceed a cap is skipped for the next one
    a = torch.zeros(1, 3, 3)
    a[0, 0, 1], a[0, 2, 1], a[0, 0, 2], a[0, 1, 0] = 0.9, 0.8, 0.7, 0.1
    take = greedy_hard_attention(a, 1)[0]
    assert take.nonzero().tolist() == [[0, 1], [1, 0]]  # (2,1): out of 1 used; (0,2): in of 0 used


def test_tree_json_round_trip_and_torch_prediction_match_sklearn():
    import pytest

    pytest.importorskip("sklearn")
    from fixtures import feature_map
    from neurosym_cli.synth.tree import TreeModel, fit_tree

    env, pol, data = _setup(rollouts=2)
    b = data[-1]
    feats = feature_map("formation").view(b.agent, b.rel)
    x = torch.stack([feats[f].expand(b.states, b.n_agents, b.n_agents) for f in feats.names], -1)
    y = (feats["d"] < 3.0) & (feats["dx"] > 0)  # a rule a tree can learn exactly
    tree, info = fit_tree(x.reshape(-1, x.shape[-1]), y.flatten(), feats.names, (3, 5), 0)
    assert max(info["validation_accuracy"].values()) > 0.99
    again = TreeModel.from_json(tree.to_json())
    assert again == tree
    pred = again.predict(feats)
    assert (pred == y).float().mean() > 0.99


def test_single_leaf_tree_predicts_its_class():
    from fixtures import feature_map
    from neurosym_cli.synth.tree import TreeModel

    feats = feature_map("formation").view(torch.zeros(2, 3, 2), torch.randn(2, 3, 3, 2))
    for label in (True, False):
        tree = TreeModel(["d"], [-1], [-1], [-2], [-2.0], [label])
        assert (tree.predict(feats) == label).all()


def _rule_zoo(space, rng):
    """Sampled rules plus hand-made corner cases: agent-level filters and scores (every candidate ties), zero and
    multi-term linear forms, filters that pass nobody, or-of-agent-tests, deeper filters (torch fallback)."""
    from neurosym_cli.dsl import And, Or, Test

    zoo = [r for _ in range(60) for r in random_rules(space, rng)]
    g = Test(Linear((("gtheta", 1.0),)), 0.3)
    d = Test(Linear((("d", 1.0),)), 2.5)
    zoo += [ArgMaxRule(Linear((("gd", 1.0),)), TrueCond()), ArgMaxRule(Linear((("gx", -1.0),)), d),
            ArgMaxRule(Linear(()), And(g, d)), RandomRule(Or(g, d)), RandomRule(Or(g, Test(Linear((("gy", 1.0),)), 0.0))),
            ArgMaxRule(Linear((("theta", -1.0),)), Test(Linear((("d", 1.0),)), 1e6)),
            ArgMaxRule(Linear((("dx", 1.0), ("dy", 0.5))), TrueCond()),
            ArgMaxRule(Linear((("d", 1.0),)), Test(Linear((("dx", 1.0), ("gx", -2.0))), 0.1)),
            RandomRule(And(And(g, d), d)), ArgMaxRule(Linear((("d", 2.0),)), TrueCond())]
    return zoo


def test_compiled_rule_scans_equal_the_torch_evaluator():
    """kernels.scan_picks (first passing candidate in a precomputed order) == rule_picks (masked max over all
    pairs), ties included, for every rule shape; uncovered shapes fall back to torch."""
    from neurosym_cli.synth import kernels

    if not kernels.AVAILABLE:
        pytest.skip("numba not installed")
    env, pol, data = _setup()
    fast = CachedScorer(pol, env, data, round_idx=0, version="v1", lam=0.5, objective="paper", cap=2, samples=2,
                        gen=torch.Generator().manual_seed(1), device=CPU, backend="numba")
    ref = CachedScorer(pol, env, data, round_idx=0, version="v1", lam=0.5, objective="paper", cap=2, samples=2,
                       gen=torch.Generator().manual_seed(1), device=CPU, backend="torch")
    space = _space(ref, 2)
    covered = 0
    for k, rule in enumerate(_rule_zoo(space, random.Random(0))):
        for a, b in zip(fast.picks_of(rule, k % 2), ref.picks_of(rule, k % 2)):
            assert torch.equal(a, b), rule
        covered += kernels.rule_spec(rule, *fast.data[0].scan_inputs()[:2]) is not None
    assert covered > 100  # most rules went through the kernel


@pytest.mark.parametrize("case", ["cross", "unlabeled-round1"])
def test_compiled_and_torch_scorers_run_the_same_search(case):
    """Same seed, both back-ends: the same objective at every step (to float tolerance), the same best program;
    also for the first of two rounds (its later round is recomputed for everybody)."""
    from neurosym_cli.synth import kernels

    if not kernels.AVAILABLE:
        pytest.skip("numba not installed")
    if case == "cross":
        env, pol, data = _setup()
        rnd, objective = 0, "paper"
    else:
        task = UnlabeledConfig(name="u", horizon=6, rounds=2, agents_per_group=5)
        env, pol, data = _setup(task, rounds=2, rollouts=3)
        rnd, objective = 0, "hinge"
    runs = []
    for backend in ("numba", "torch"):
        sc = CachedScorer(pol, env, data, round_idx=rnd, version="v1", lam=0.5, objective=objective, cap=3, samples=1,
                          gen=torch.Generator().manual_seed(1), device=CPU, backend=backend)
        space = _space(sc, 3)
        rng = random.Random(5)
        res = metropolis(lambda: random_rules(space, rng), lambda r: propose(r, space, rng), sc, steps=150, restarts=2,
                         final_fraction=0.2, temperature=0.1, rng=rng)
        runs.append((res, sc))
    (a, sa), (b, sb) = runs
    assert a.best == b.best
    assert [r["move"] for r in a.trace] == [r["move"] for r in b.trace]
    for x, y in zip(a.trace, b.trace):
        assert abs(x["objective"] - y["objective"]) <= 1e-4 * max(1.0, abs(y["objective"]))
    assert sa.rows_recomputed == sb.rows_recomputed and sa.memo_hits == sb.memo_hits
    assert sa.rows_recomputed > 0


@pytest.mark.parametrize("backend", ["numba", "torch"])
def test_scorer_beyond_127_agents(backend):
    """Picks are stored small (int8) only up to 127 agents: a 140-agent bucket scores exactly as the full
    forward pass (before, indices above 127 wrapped around)."""
    from neurosym_cli.synth import kernels

    if backend == "numba" and not kernels.AVAILABLE:
        pytest.skip("numba not installed")
    env = make_task(CrossConfig(name="random-cross", horizon=4))
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig()).eval()
    g = torch.Generator().manual_seed(0)
    s, n = 2, 140
    pos = torch.rand(s, n, 2, generator=g) * 30
    agent = torch.randn(s, n, 2, generator=g)
    data = [DataBucket(agent, pos[:, :, None, :] - pos[:, None, :, :], torch.randn(s, n, 2, generator=g))]
    sc = CachedScorer(pol, env, data, round_idx=0, version="v1", lam=0.5, objective="paper", cap=3, samples=1,
                      gen=torch.Generator().manual_seed(1), device=CPU, backend=backend)
    far = ArgMaxRule(Linear((("d", 1.0),)), TrueCond())  # the farthest agent: often an index above 127
    picks = sc.picks_of(far)[0].long()
    assert int(picks.max()) > 127
    assert torch.equal(picks.flatten(), rule_picks(far, sc.data[0].feats, None).flatten())
    space = _space(sc, 3)
    rng = random.Random(0)
    _walk_matches_full_forward(sc, space, rng, (far,) + random_rules(space, rng)[1:])


@pytest.mark.parametrize("kind,goals,version", [("formation", 0, "v1"), ("formation", 0, "v2"), ("unlabeled", 10, "v1")])
def test_every_rule_the_search_proposes_compiles_for_the_kernels(kind, goals, version):
    """The kernels' rule specification is derived from the AST (kernels.rule_spec); every rule the search can
    propose (initial rules and neighbours of every move, with and without own-state scores) compiles to it, so
    the compiled back-end never silently falls back to torch in a search."""
    from fixtures import feature_map
    from neurosym_cli.synth import kernels

    vocab = feature_map(kind, version, goals).vocab
    names = vocab.names
    agent_level = vocab.agent_level
    pair, agent = [n for n in names if not agent_level(n)], [n for n in names if agent_level(n)]
    rng = random.Random(0)
    for own_scores in (True, False):
        space = SearchSpace({n: (-1.0, 0.0, 1.0) for n in names}, rules=3, own_scores=own_scores,
                            own=frozenset(agent))
        rules = random_rules(space, rng)
        for _ in range(400):
            rules, _move = propose(rules, space, rng)
            for r in rules:
                assert kernels.rule_spec(r, pair, agent) is not None, r
                if not own_scores and isinstance(r, ArgMaxRule):
                    assert not all(agent_level(n) for n, _ in r.score.terms), r


def _planted_scorer(lam=0.0):
    """The planted-program fixture: targets made by the transformer hearing only the nearest agent."""
    from fixtures import feature_map

    env, pol, data = _setup(rollouts=4)
    planted = ArgMaxRule(Linear((("d", -1.0),)), TrueCond())
    planted_data = []
    for b in data:
        feats = feature_map("formation").view(b.agent, b.rel)
        with torch.no_grad():
            out = pol(Observation(b.agent, b.rel),
                      lambda logits, r: picks_to_mask(rule_picks(planted, feats, None)[..., None], b.n_agents))
        planted_data.append(DataBucket(b.agent, b.rel, env.target(out.action)))
    return planted, CachedScorer(pol, env, planted_data, round_idx=0, version="v1", lam=lam, objective="paper", cap=3,
                                 samples=1, gen=torch.Generator().manual_seed(0), device=CPU)


def test_never_holds_finds_contradictions():
    from neurosym_cli.dsl.parser import parse
    from fixtures import feature_map
    from neurosym_cli.synth.simplify import never_holds as _never

    vocab = feature_map("formation").vocab

    def never_holds(c):
        return _never(c, vocab)

    def c(text):
        return parse(f"random(filter({text}, l))").rounds[0][0].cond

    assert never_holds(c("d >= 3.0 and d <= 2.0"))
    assert never_holds(c("d <= -1.0"))  # a distance is never negative
    assert never_holds(c("theta >= 4.0"))  # an angle is at most pi
    assert never_holds(c("dx >= 1.0 and gd >= 0.5 and dx <= 0.0"))
    assert not never_holds(c("d >= 2.0 and d <= 3.0"))
    assert not never_holds(c("d >= 3.0 and d <= 2.0 or dx >= 0.0"))
    assert never_holds(c("d >= 3.0 and d <= 2.0 or theta <= -4.0"))


def test_rule_statistics_on_a_hand_built_program():
    from neurosym_cli.dsl.parser import parse
    from neurosym_cli.synth.simplify import rule_stats

    planted, sc = _planted_scorer()
    rules = (planted,) + parse("random(filter(d <= -1.0, l))\nargmax(map(-1.0*d, filter(true, l)))\n").rounds[0]
    stats = rule_stats(sc, rules)
    assert [s["fires"] for s in stats] == [1.0, 0.0, 1.0]
    assert stats[0]["edge_share"] == 1.0 and stats[2]["edge_share"] == 0.0  # rule 3 repeats rule 1's picks
    assert "always fires" in stats[0]["flags"] and "never fires" in stats[1]["flags"]
    assert any("can never hold" in f for f in stats[1]["flags"])
    assert stats[1]["removal_delta"] == pytest.approx(0.0, abs=1e-9)  # it does nothing
    assert stats[2]["removal_delta"] == pytest.approx(0.0, abs=1e-9)  # its edges are rule 1's
    assert stats[0]["removal_delta"] == pytest.approx(0.0, abs=1e-9)  # ... and rule 3 would take them over


def test_simplification_keeps_the_objective_on_the_planted_program():
    from neurosym_cli.dsl.parser import parse
    from neurosym_cli.dsl.printer import rule_text
    from neurosym_cli.synth.simplify import simplify

    planted, sc = _planted_scorer(lam=0.5)
    noisy = parse("argmax(map(-1.0*d, filter(d >= 0.0 and d <= -1.0 or dx <= 1000.0, l)))\n"
                  "random(filter(d <= -1.0, l))\n").rounds[0]
    before = sc.score(noisy)
    simple, done = simplify(sc, noisy)
    after = sc.score(simple)
    assert after.total <= before.total + 1e-9
    assert [rule_text(r) for r in simple] == ["argmax(map(-1.0*d, filter(dx <= 1000.0, l)))"] or \
        [rule_text(r) for r in simple] == ["argmax(map(-1.0*d, filter(true, l)))"]
    assert sc.score(simple).l1 == pytest.approx(sc.score((planted,)).l1, abs=1e-6)
    assert any("can never hold" in line or "became `true`" in line for line in done)
    assert any("never fires" in line for line in done)
    # a program with nothing to drop comes back unchanged
    assert simplify(sc, (planted,)) == ((planted,), [])


def test_simplification_of_a_filter_that_always_holds_and_a_repeated_rule():
    """The paper-budget random-cross program's last rule: its filter always holds (a distance is never below
    -0.6), so it is `argmax(map(-1.0*d, filter(true, l)))`, the first rule again: it adds no edge and goes."""
    from neurosym_cli.dsl.parser import parse
    from neurosym_cli.synth.simplify import always_holds, simplify

    planted, sc = _planted_scorer(lam=0.5)
    rules = (planted,) + parse("argmax(map(-1.0*d, filter(theta <= 2.22 or d >= -0.6, l)))\n").rounds[0]
    v = sc.fmap.vocab
    assert always_holds(rules[1].cond, v) and not always_holds(parse("random(filter(d >= 0.5, l))").rounds[0][0].cond, v)
    before = sc.score(rules).total
    simple, done = simplify(sc, rules)
    assert simple == (planted,) and sc.score(simple).total == pytest.approx(before, abs=1e-9)
    assert "became `true` (always holds)" in done[0] and "only repeats earlier rules' picks" in done[1]


def test_a_one_feature_or_that_covers_the_range_always_holds_and_a_negative_distance_never_does():
    """The main job's det-prog had `filter(d <= 2.85 or d >= 2.56, l)` (every distance passes one branch), and a
    committed random-cross program a rule on `d <= -0.3` (no distance is negative): both go, with or without D."""
    from neurosym_cli.dsl.parser import parse
    from neurosym_cli.dsl.printer import rule_text
    from neurosym_cli.synth.simplify import always_holds, never_holds, simplify, simplify_static

    planted, sc = _planted_scorer(lam=0.5)
    v = sc.fmap.vocab

    def c(text):
        return parse(f"random(filter({text}, l))").rounds[0][0].cond

    assert always_holds(c("d <= 2.85 or d >= 2.56"), v) and always_holds(c("d <= 2.5 or d >= 2.5"), v)
    assert always_holds(c("dx <= 1.0 or gd >= 3.0 or dx >= 0.5"), v)  # the dx branches cover every dx
    assert not always_holds(c("d <= 2.5 or d >= 2.6"), v) and not always_holds(c("dx <= 1.0 or dy >= 0.5"), v)
    assert never_holds(c("d <= -0.3 and gtheta <= -1.75"), v)
    rules = parse("argmax(map(-1.0*d, filter(d <= 2.85 or d >= 2.56, l)))\n").rounds[0]
    simple, done = simplify(sc, rules)
    assert [rule_text(r) for r in simple] == ["argmax(map(-1.0*d, filter(true, l)))"] and "always holds" in done[0]
    rules = parse("argmax(map(-1.0*d, filter(true, l)))\nargmax(map(-1.0*gd, filter(d <= -0.3 and gtheta <= -1.75, l)))\n"
                  "random(filter(d >= -1.0 and gd <= 3.0 or d <= -2.0, l))\n").rounds[0]
    simple, notes = simplify_static(rules, v)
    assert [rule_text(r) for r in simple] == ["argmax(map(-1.0*d, filter(true, l)))", "random(filter(gd <= 3.0, l))"]
    assert "rule 2: dropped" in notes[0] and "never fires" in notes[0] and len(notes) == 3


@pytest.mark.parametrize("backend", ["numba", "torch"])
def test_large_data_fallback_scores_as_the_cached_messages_on_a_4_wide_task(backend, monkeypatch):
    """Beyond prepared.MESSAGES_MAX_PAIRS the scorer recomputes the picked messages from the pair observations
    instead of gathering cached ones; on the ring example (Dp = 4) both paths, and the full forward pass, give the
    same scores (before, the fallback read the pair observations as 2-wide rows)."""
    from neurosym_cli.synth import kernels, prepared

    if backend == "numba" and not kernels.AVAILABLE:
        pytest.skip("numba not installed")
    monkeypatch.syspath_prepend(str(ROOT / "examples" / "ring"))
    from ring import RingConfig, RingTask

    env = RingTask(RingConfig(horizon=6, agents_per_group=5))
    assert env.pair_dim == 4
    torch.manual_seed(0)
    pol = CommTransformer.for_task(env, ModelConfig()).eval()
    data = collect(env, pol, 3, 2, torch.Generator().manual_seed(0), CPU)

    def scorer():
        return CachedScorer(pol, env, data, round_idx=0, version="v1", lam=0.5, objective="paper", cap=2, samples=1,
                            gen=torch.Generator().manual_seed(1), device=CPU, backend=backend)

    cached = scorer()
    monkeypatch.setattr(prepared, "MESSAGES_MAX_PAIRS", 0)
    fallback = scorer()
    assert cached.data[0].messages is not None and fallback.data[0].messages is None
    space = _space(cached, 2)
    rng = random.Random(0)
    rules = random_rules(space, rng)
    for _ in range(15):
        a, b = cached.score(rules), fallback.score(rules)
        full = fallback.full_score(Program((rules,)))
        assert abs(a.l1 - b.l1) <= 1e-4 * max(1.0, a.l1) and abs(b.l1 - full.l1) <= 1e-4 * max(1.0, full.l1)
        assert a.degree == b.degree
        cached.accept()
        fallback.accept()
        rules, _ = propose(rules, space, rng)
