"""The trade-off in the task's own units (synth.objective=scaled), the degree-budget front and the guard (issue 37)."""

import json
import math
import random

import pytest
import torch
from hydra import compose, initialize_config_module

import neurosym_cli.commands.apps  # noqa: F401  (registers the schema)
from neurosym_cli.commands._run import typed_config
from neurosym_cli.config import ModelConfig, RunConfig, SynthConfig, TaskConfig
from neurosym_cli.dsl import ArgMaxRule, Linear, RandomRule, TrueCond
from neurosym_cli.dsl.interpret import picks_to_mask, rule_picks
from neurosym_cli.dsl.sampling import SearchSpace, propose, random_rules
from neurosym_cli.helptext import command_help
from neurosym_cli.policy import CommTransformer
from neurosym_cli.stages.guard import communication_guard
from neurosym_cli.synth.dataset import DataBucket, collect
from neurosym_cli.synth.front import search_front, silence
from neurosym_cli.synth.mcmc import metropolis
from neurosym_cli.synth.objective import CachedScorer
from neurosym_cli.synth.search import RoundSpec, feature_quantiles
from neurosym_cli.tasks import Observation, make_task
from neurosym_cli.tasks.random_cross import CrossConfig

CPU = torch.device("cpu")
NEAREST = ArgMaxRule(Linear((("d", -1.0),)), TrueCond())
"""hear the nearest agent"""


class _Scaled:
    """A task whose actions are ``k`` times the wrapped task's: the same task in other units."""

    def __init__(self, env, k: float):
        self.env, self.k = env, k

    def target(self, out):
        return self.k * self.env.target(out)

    def features(self, version):
        return self.env.features(version)


def _setup(rollouts=4):
    env = make_task(CrossConfig(name="random-cross", horizon=12))
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig()).eval()
    return env, pol, collect(env, pol, rollouts, 2, torch.Generator().manual_seed(0), CPU)


def _scorer(env, pol, data, *, objective, lam, cap):
    return CachedScorer(pol, env, data, round_idx=0, version="v1", lam=lam, objective=objective, cap=cap, samples=1,
                        gen=torch.Generator().manual_seed(0), device=CPU)


def _planted(cap=1):
    """Targets made by the transformer hearing only its nearest agent: NEAREST scores L1 = 0."""
    env, pol, data = _setup()
    fmap = env.features("v1")
    planted = []
    for b in data:
        feats = fmap.view(b.agent, b.rel)
        with torch.no_grad():
            out = pol(Observation(b.agent, b.rel),
                      lambda logits, r: picks_to_mask(rule_picks(NEAREST, feats, None)[..., None], b.n_agents))
        planted.append(DataBucket(b.agent, b.rel, env.target(out.action)))
    return env, pol, planted


# ------------------------------------------------------------------------------------------ scaled objective
def test_silence_scores_one_and_the_paper_form_is_unchanged():
    env, pol, data = _setup()
    k = 2
    sc = _scorer(env, pol, data, objective="scaled", lam=0.25, cap=k)
    quiet = sc.score(silence("d", k))
    assert quiet.degree == 0 and quiet.total == pytest.approx(1.0, rel=1e-6)
    assert sc.scale.degree == 2 * k and sc.scale.l1 == pytest.approx(quiet.l1, rel=1e-6)
    prog = (NEAREST, RandomRule(TrueCond()))
    s = sc.score(prog)
    assert s.total == pytest.approx(s.l1 / quiet.l1 + 0.25 * s.degree / (2 * k), rel=1e-9)
    paper = _scorer(env, pol, data, objective="paper", lam=0.5, cap=k)
    p = paper.score(prog)
    assert paper.scale is None and p.total == p.l1 + 0.5 * p.degree  # the paper's float operations, bit for bit
    assert (p.l1, p.degree) == (s.l1, s.degree)  # the terms are the same; only their weighting differs


def test_the_scaled_choice_does_not_depend_on_the_task_units_where_the_papers_does():
    env, pol, data = _setup()
    k = 2
    candidates = [silence("d", k), (NEAREST, silence("d", 1)[0]), (NEAREST, RandomRule(TrueCond())),
                  (RandomRule(TrueCond()), RandomRule(TrueCond()))]
    base = _scorer(env, pol, data, objective="paper", lam=0.0, cap=k)
    terms = [base.score(c) for c in candidates]
    gain = max((terms[0].l1 - t.l1) / t.degree for t in terms[1:])
    lam_paper = 2.0 * gain  # in 1x units no program buys its degree back: silence wins; in 10x units it does not

    def choice(objective, lam, units):
        sc = _scorer(_Scaled(env, units), pol, [DataBucket(b.agent, b.rel, units * b.target) for b in data],
                     objective=objective, lam=lam, cap=k)
        totals = [sc.score(c).total for c in candidates]
        return min(range(len(candidates)), key=totals.__getitem__), totals

    paper1, _ = choice("paper", lam_paper, 1.0)
    paper10, _ = choice("paper", lam_paper, 10.0)
    assert paper1 == 0 and paper10 != 0  # the paper's lam means another trade-off in other units
    for lam in (0.1, 0.25, 1.0):
        one, t1 = choice("scaled", lam, 1.0)
        ten, t10 = choice("scaled", lam, 10.0)
        assert one == ten
        assert t10 == pytest.approx(t1, rel=1e-5)


def test_scaled_objective_refuses_an_oracle_that_ignores_its_messages():
    from neurosym_cli.errors import UserError

    env, pol, _ = _setup()
    with torch.no_grad():  # messages that carry nothing: every program acts as silence does
        for layer in pol.rounds:
            layer.out.weight.zero_()
    data = collect(env, pol, 2, 2, torch.Generator().manual_seed(0), CPU)
    with pytest.raises(UserError, match="nothing to trade"):
        _scorer(env, pol, data, objective="scaled", lam=0.25, cap=2)


def test_tasks_that_state_no_objective_get_the_scaled_one_and_the_papers_keep_theirs():
    def synth_cfg(task):
        with initialize_config_module("neurosym_cli.conf", version_base="1.3"):
            return typed_config(compose("synth", overrides=[f"task={task}"]))

    for task, lam in (("random-cross", 0.5), ("random-grid", 0.5), ("two-groups-cross", 0.5),
                      ("unlabeled-goals", 0.7), ("random-grid-noisy", 0.5)):
        cfg = synth_cfg(task)
        assert (cfg.synth.objective, cfg.lam) == ("paper", lam), task
    for task in ("swarm", "vmas/navigation"):
        cfg = synth_cfg(task)
        assert (cfg.synth.objective, cfg.lam) == ("scaled", 0.25), task
    assert (RunConfig.lam, SynthConfig.objective) == (TaskConfig.lam, TaskConfig.objective) == (0.25, "scaled")


def test_help_of_a_task_without_its_own_trade_off_shows_the_scaled_default_and_its_meaning():
    def help_of(task):
        with initialize_config_module("neurosym_cli.conf", version_base="1.3"):
            cfg = typed_config(compose("synth", overrides=[f"task={task}"]))
        return " ".join(command_help("synth", cfg, lambda g: []).split())

    out = help_of("swarm")
    assert "lam=0.25 weight of the degree term in synth.objective's units" in out
    assert "synth.objective=scaled the synthesis objective's form" in out
    assert all(form in out for form in ("scaled (L1 / L1(silence on D)", "paper (L1 + lam", "hinge (L1 + lam"))
    assert "lambda-tilde: weight" not in out  # the paper's name is not the meaning of every task's lam
    out = help_of("two-groups-cross")
    assert "lam=0.5 weight of the degree term" in out and "synth.objective=paper the synthesis" in out


# ------------------------------------------------------------------------------------------ the front
def _archive(sc, k, steps, seed=3):
    space = SearchSpace(feature_quantiles(sc, torch.Generator().manual_seed(0)), k, 2, True)
    rng = random.Random(seed)
    res = metropolis(lambda: random_rules(space, rng), lambda r: propose(r, space, rng), sc, steps=steps, restarts=2,
                     final_fraction=0.3, temperature=0.1, rng=rng)
    return [rules for _, rules in res.hall.by_degree.values()]


def _spec(k, det=True):
    return RoundSpec(steps=0, restarts=0, final_fraction=0.2, temperature=0.1, rules=k, max_depth=2, det=det)


def test_the_front_is_monotone_and_within_its_budgets():
    env, pol, data = _setup()
    k = 2
    sc = _scorer(env, pol, data, objective="paper", lam=0.3, cap=k)
    budgets = [0.0, 1.0, 2.0, 3.0, 4.0, 6.0]
    rows, _ = search_front(sc, _spec(k, det=False), archive=_archive(sc, k, 60), budgets=budgets, steps=25,
                           seed="front", gen=torch.Generator().manual_seed(1))
    assert [r["budget"] for r in rows] == budgets
    assert rows[0]["degree"] == 0 and rows[0]["l1_ratio"] == pytest.approx(1.0) and rows[0]["source"] == "silence"
    for a, b in zip(rows, rows[1:]):
        assert b["l1"] <= a["l1"]  # a larger budget never has a worse best L1
    for r in rows:
        assert r["degree"] <= r["budget"] + 1e-9
        assert r["max_in"] <= k + 1e-9 and r["max_in"] <= r["degree"] + 1e-9 and r["max_out"] <= r["degree"] + 1e-9


def test_det_progs_front_holds_argmax_rules_only():
    """det-prog's front (the ablation without random rules, appendix B): its chains start from silence, so silence
    must be written in argmax rules too, or a chain mutating its filters keeps random rules in every budget."""
    env, pol, data = _setup()
    k = 2
    sc = _scorer(env, pol, data, objective="paper", lam=0.3, cap=k)
    rows, _ = search_front(sc, _spec(k, det=True), archive=[], budgets=[0.0, 1.0, 2.0, 4.0], steps=25,
                           seed="front", gen=torch.Generator().manual_seed(1))
    assert rows[0]["degree"] == 0 and rows[0]["l1_ratio"] == pytest.approx(1.0)
    assert rows[-1]["degree"] > 0  # the chains moved off silence
    for r in rows:
        assert "random(" not in r["program"] and r["program"].startswith("argmax("), r["program"]
    assert all(isinstance(rule, ArgMaxRule) for rule in silence("d", k, det=True))


def test_a_det_front_that_does_not_parse_is_searched_again_not_a_traceback(tmp_path):
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.run import RunDir
    from neurosym_cli.stages.synth import front_stale

    cfg = compose_config("synth", [f"runs_root={tmp_path}", "task=two-groups-cross", "budget=tiny", "baseline=det-prog"])
    front = RunDir(cfg).front_file
    front.parent.mkdir(parents=True)
    front.write_text(json.dumps({"rounds": [{"budgets": [{"program": "argmax(map(d, filter(d <=, l)))"}]}]}))
    assert front_stale(cfg)  # a program that does not parse: searched again
    prog = compose_config("synth", [f"runs_root={tmp_path}", "task=two-groups-cross", "budget=tiny"])
    RunDir(prog).front_file.parent.mkdir(parents=True)
    RunDir(prog).front_file.write_text("not json")
    assert not front_stale(prog)  # prog's space holds every rule: only det-prog's fronts can leave it
    dt = compose_config("synth", [f"runs_root={tmp_path}", "task=two-groups-cross", "budget=tiny", "baseline=dt"])
    assert not front_stale(dt)  # a tree: no front, no det


def test_a_planted_program_is_recovered_at_its_budget():
    env, pol, data = _planted()
    sc = _scorer(env, pol, data, objective="paper", lam=0.0, cap=1)
    planted = sc.score((NEAREST,))
    assert planted.l1 < 1e-5 and planted.degree > 0
    at = math.ceil(planted.degree)
    rows, _ = search_front(sc, _spec(1), archive=_archive(sc, 1, 300), budgets=[0.0, float(at), float(at + 2)],
                           steps=40, seed="planted", gen=torch.Generator().manual_seed(1))
    assert rows[0]["l1"] > 1e-2  # silence does not act as the nearest agent's listener
    for r in rows[1:]:
        assert r["l1"] < 1e-3, r
        assert r["degree"] <= planted.degree + 1e-6  # the planted program, or one that picks as it does


def test_the_sparse_end_offers_the_nearest_agent_within_the_largest_radius_in_budget():
    """synth/front.range_rows: per budget 1, 2, 3 the nearest-within-r program of the largest quantile radius whose
    max in+out on D is within it; radius and degree grow with the budget; the text parses back to that program;
    a radius past every distance is the planted nearest-agent program (L1 0 on its own targets)."""
    from neurosym_cli.dsl.parser import parse
    from neurosym_cli.synth.front import nearest_radii, nearest_within, range_rows

    env, pol, data = _planted()
    sc = _scorer(env, pol, data, objective="paper", lam=0.0, cap=1)
    unit = sc.silent_l1()
    radii = (0.5, 1.0, 2.0, 4.0, 8.0, 1e6)
    rows = range_rows(sc, radii, [0.0, 1.0, 2.0, 3.0, 6.0], unit)
    assert rows and [r["budget"] for r in rows] == sorted(r["budget"] for r in rows)
    for r in rows:
        assert r["degree"] <= r["budget"] + 1e-9 and r["source"] == "range"
        assert parse(r["program"]).rounds[0] == nearest_within(r["radius"])
        bigger = [x for x in radii if x > r["radius"]]
        if bigger:  # the next radius would exceed the budget
            assert sc.score(nearest_within(bigger[0])).degree > r["budget"] + 1e-9
    for a, b in zip(rows, rows[1:]):
        assert b["radius"] >= a["radius"] and b["degree"] >= a["degree"]
    radii_d = nearest_radii(sc)  # the grid the front uses: quantiles of each agent's nearest distance on D
    nn = torch.cat([d.feats["d"].expand(d.s, d.n, d.n).masked_fill(torch.eye(d.n, dtype=torch.bool), float("inf"))
                    .amin(-1).flatten() for d in sc.data])
    assert list(radii_d) == sorted(set(radii_d)) and len(radii_d) > 3
    assert float(nn.min()) - 0.01 <= radii_d[0] and radii_d[-1] <= float(nn.max()) + 0.01
    top = sc.score(nearest_within(1e6))
    assert top.l1 < 1e-5  # within every distance: the nearest agent, the planted program
    assert range_rows(sc, radii, [0.0], unit) == []  # no budget of the sparse end asked for


# ------------------------------------------------------------------------------------------ the guard
def _row(label, cost, ci=0.1, degree=4.0):
    return (label, {"cost": {"mean": cost, "ci95": ci}, "max_degree": {"mean": degree, "ci95": 0.0}})


LABELS = ("prog-retrained-k2-lam0.5-v1", "prog-k2-lam0.5-v1")
"""the run's own program labels, as results.print_table passes them"""


def test_the_guard_fires_when_communication_helps_and_the_program_is_silent_or_worse():
    rows = [_row("tf-full", 3.66), _row("prog-k2-lam0.5-v1", 6.5, degree=0.0),
            _row("prog-retrained-k2-lam0.5-v1", 6.08, degree=0.0), _row("no-comm", 4.55, degree=0.0)]
    line = communication_guard(rows, labels=LABELS, rerun="neurosym synth baseline=prog task=mine budget=quick seed=0")
    assert line and "\n" not in line
    assert "prog-retrained-k2-lam0.5-v1 is silent" in line and "synth.front=true" in line and "smaller lam" in line
    worse = [_row("tf-full", 3.66), _row("prog-retrained-k2-lam0.5-v1", 4.9, degree=3.0), _row("no-comm", 4.55)]
    assert "does no better than no-comm" in communication_guard(worse, labels=LABELS)
    # the show-program it names runs as printed: the run's own (results.print_table passes run.show_command's)
    show = "neurosym show-program task=mine rules=2 lam=0.5 features=v1 budget=quick seed=0"
    for front in (True, False):
        line = communication_guard(rows, labels=LABELS, show=show, settings={"synth.front": front})
        assert f"`{show}`" in line and "`neurosym show-program`" not in line


def test_the_guard_judges_the_runs_own_program_not_the_first_label_in_sort_order():
    # a user's program= file and an older single-lam result sort before the run's program: neither is judged
    rows = [_row("tf-full", 3.66), _row("no-comm", 4.55),
            _row("prog-retrained-file-mine-0123abcd-v1", 6.0, degree=0.0),
            _row("prog-retrained-k2-lam0.1-v1", 6.0, degree=0.0),
            _row("prog-retrained-k2-lam0.5-v1", 4.0, degree=3.0)]
    assert communication_guard(rows, labels=LABELS) is None
    rows[-1] = _row("prog-retrained-k2-lam0.5-v1", 6.2, degree=0.0)
    line = communication_guard(rows, labels=LABELS)
    assert line and "prog-retrained-k2-lam0.5-v1 is silent" in line and "lam0.1" not in line and "file" not in line
    # the run's program not evaluated (yet): nothing said about another's
    assert communication_guard(rows[:-1], labels=LABELS) is None


def test_the_guard_suggests_no_lever_already_in_effect():
    rows = [_row("tf-full", 3.66), _row("prog-retrained-k2-lam0.5-v1", 6.08, degree=0.0), _row("no-comm", 4.55)]
    plain = communication_guard(rows, labels=LABELS, settings={"synth.objective": "paper", "synth.search": "mcmc",
                                                                "synth.front": False})
    assert "synth.objective=scaled" in plain and "synth.search=hybrid" in plain and "synth.front=true" in plain
    scaled = communication_guard(rows, labels=LABELS, settings={"synth.objective": "scaled",
                                                                 "synth.search": "hybrid", "synth.front": True})
    assert scaled and "synth.objective=scaled" not in scaled and "synth.search=hybrid" not in scaled
    assert "synth.front=true" not in scaled and "show-program" in scaled  # a higher budget of the front it has


def test_the_guard_decides_communication_helps_by_the_paired_rule_where_per_seed_rows_exist():
    from neurosym_cli.stages.front_select import communication_helps as front_rule
    from neurosym_cli.stages.guard import communication_helps

    assert front_rule is communication_helps  # one rule for the guard and pipeline.select=front
    # the intervals overlap (wide, seed-to-seed spread) but no-comm is worse on every seed by about 0.5: paired, it
    # helps; the unpaired reading said nothing
    tf = {s: 3.0 + s for s in range(6)}
    nc = {s: 3.5 + s + 0.01 * (s % 2) for s in range(6)}
    rows = [_row("tf-full", 5.5, ci=2.0), _row("no-comm", 6.0, ci=2.0),
            _row("prog-retrained-k2-lam0.5-v1", 6.5, degree=0.0)]
    assert communication_guard(rows, labels=LABELS) is None
    line = communication_guard(rows, labels=LABELS, per_seed={"tf-full": tf, "no-comm": nc})
    assert line and "is silent" in line
    # and the other way: intervals apart, but the paired differences scatter around 0 -> no line
    rows = [_row("tf-full", 3.0, ci=0.01), _row("no-comm", 4.0, ci=0.01),
            _row("prog-retrained-k2-lam0.5-v1", 6.5, degree=0.0)]
    assert communication_guard(rows, labels=LABELS)
    tf = {0: 1.0, 1: 5.0, 2: 3.0}
    nc = {0: 5.0, 1: 1.0, 2: 3.1}
    assert communication_guard(rows, labels=LABELS, per_seed={"tf-full": tf, "no-comm": nc}) is None


@pytest.mark.parametrize("rows", [
    [_row("tf-full", 4.5), _row("prog-retrained-k2-lam0.5-v1", 6.0, degree=0.0), _row("no-comm", 4.55)],  # a tie
    [_row("tf-full", 3.66), _row("prog-retrained-k2-lam0.5-v1", 4.1, degree=3.0), _row("no-comm", 4.55)],  # works
    [_row("tf-full", 3.66), _row("no-comm", 4.55)],  # no program evaluated
    [_row("prog-retrained-k2-lam0.5-v1", 6.0, degree=0.0), _row("no-comm", 4.55)],  # no tf-full
])
def test_the_guard_stays_quiet_otherwise(rows):
    assert communication_guard(rows, labels=LABELS) is None
