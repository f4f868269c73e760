"""Model selection by validation (`neurosym select`), the search's hall of fame and the early-stopping levers."""

import json
import random

import pytest
import torch

from conftest import PAPER_METHOD
from test_cli import run


# --- the selection rule ---------------------------------------------------------------------------------------

def _row(name, losses, degree):
    return {"name": name, "loss": losses, "degree": degree}


def test_a_tie_inside_the_interval_goes_to_the_lower_degree():
    from neurosym_cli.stages.select import choose

    base = [10.0, 11.0, 9.5, 10.5, 10.2, 9.8]
    noisy = [x + d for x, d in zip(base, (0.3, -0.2, 0.25, -0.3, 0.1, -0.05))]  # mean +0.017: not significant
    worse = [x + 1.0 + d for x, d in zip(base, (0.1, -0.1, 0.05, 0.0, -0.05, 0.02))]  # clearly worse, lowest degree
    out = choose([_row("best", base, 8.0), _row("similar", noisy, 3.0), _row("worse", worse, 1.0)])
    by = {r["name"]: r for r in out}
    assert by["best"]["best"] and by["best"]["similar"] and by["similar"]["similar"]
    assert not by["worse"]["similar"] and by["worse"]["diff"] > by["worse"]["diff_ci"]
    assert [r["name"] for r in out if r["picked"]] == ["similar"]  # similar loss, lower degree
    assert out[0]["name"] == "similar" and out[-1]["name"] == "worse"


def test_equal_degrees_go_to_the_lower_loss_and_a_single_row_is_picked():
    from neurosym_cli.stages.select import choose
    from neurosym_cli.stats import mean_ci, t95

    a = [1.0, 2.0, 3.0]
    b = [1.1, 2.05, 3.0]
    out = choose([_row("b", b, 2.0), _row("a", a, 2.0)])
    assert [r["name"] for r in out if r["picked"]] == ["a"]
    assert choose([_row("only", a, 5.0)])[0]["picked"]
    m, h = mean_ci([1.0, 3.0])
    assert m == 2.0 and h == pytest.approx(12.706 * 2 ** 0.5 / 2 ** 0.5)  # t with 1 degree of freedom
    assert t95(10) == 2.262 and t95(100) == pytest.approx(1.9842, abs=1e-4)  # t, never the normal 1.96
    with pytest.raises(ValueError, match="different numbers of seeds"):
        choose([_row("a", a, 1.0), _row("b", [1.0], 1.0)])


def test_a_reference_from_another_family_sets_the_loss_to_match():
    """An ablation is read at the method's loss (front_select.Family.matches): the lowest degree within the margin of
    the reference where it is better than the rows' own best; the closest row where none is; ignored where worse."""
    from neurosym_cli.stages.front_select import pick
    from neurosym_cli.stages.select import choose

    base = [10.0, 11.0, 9.5, 10.5, 10.2, 9.8]
    rows = [_row("dense", [x + 0.5 for x in base], 6.0), _row("mid", [x + 0.7 for x in base], 3.0),
            _row("sparse", [x + 1.4 for x in base], 1.0)]
    alone = choose(rows, margin=0.1)  # within 10 % of its own best (+0.9 of 10.7): the sparsest
    assert [r["name"] for r in alone if r["picked"]] == ["sparse"]
    matched = choose(rows, margin=0.1, reference=base)  # within 10 % of the reference: 'sparse' is 14 % above
    assert [r["name"] for r in matched if r["picked"]] == ["mid"]
    assert {r["name"]: r for r in matched}["dense"]["best"]  # its own best stays marked
    strict = choose(rows, margin=0.001, reference=base)  # nothing within 0.1 % of it: the lowest loss
    assert [r["name"] for r in strict if r["picked"]] == ["dense"] and not any(r["similar"] for r in strict)
    worse = choose(rows, margin=0.1, reference=[x + 5.0 for x in base])  # a worse reference changes nothing
    assert [(r["name"], r["similar"]) for r in worse] == [(r["name"], r["similar"]) for r in alone]
    assert [r["name"] for r in pick(rows, helps=True, margin=0.1, reference=base) if r["picked"]] == ["mid"]
    with pytest.raises(ValueError, match="different numbers of seeds"):
        choose(rows, reference=base[:3])


def test_validation_episodes_are_never_test_episodes():
    from neurosym_cli.tasks.random_cross import CrossConfig
    from neurosym_cli.tasks import make_task
    from neurosym_cli.utils.seeding import STREAM_EVAL, STREAM_VAL, generator

    env = make_task(CrossConfig(name="random-cross", agents_per_group=3), 5)
    starts = {}
    for split, stream in (("test", STREAM_EVAL), ("val", STREAM_VAL)):
        for s in range(20):
            eps, _ = env.test_episodes(lambda k, s=s: generator(s, stream, k))
            starts[split] = starts.get(split, []) + [e.pos.flatten() for e in eps]
    for v in starts["val"]:
        assert all(v.shape != t.shape or not torch.allclose(v, t) for t in starts["test"])


# --- the hall of fame and the search levers ----------------------------------------------------------------------

def test_hall_of_fame_rows_are_non_dominated():
    from neurosym_cli.dsl.ast import ArgMaxRule, Linear, RandomRule, Test, TrueCond
    from neurosym_cli.synth.mcmc import HallOfFame, complexity
    from neurosym_cli.synth.objective import Score

    r0 = RandomRule(TrueCond())
    r1 = RandomRule(Test(Linear((("d", 1.0),)), 2.0))
    a0 = ArgMaxRule(Linear((("d", -1.0),)), TrueCond())
    assert complexity((r0, a0)) == 2 and complexity((r1, a0)) == 3
    h = HallOfFame()
    h.add((r0, a0), Score(5.0, 3.0, 4.0))   # complexity 2
    h.add((r1, a0), Score(6.0, 2.0, 8.0))   # complexity 3, worse objective: dominated by the simpler one
    h.add((r1, r1), Score(4.0, 3.5, 1.0))   # complexity 4, better
    front = h.front("complexity")
    assert [lvl for lvl, _, _ in front] == [2, 4]
    assert all(b[1].total < a[1].total for a, b in zip(front, front[1:]))
    deg = h.front("degree")  # levels 1, 4, 8: L1 3.5, 3.0, 2.0 -- each beats every lower level
    assert [lvl for lvl, _, _ in deg] == [1, 4, 8]
    assert all(b[1].l1 < a[1].l1 for a, b in zip(deg, deg[1:]))


class _Bowl:
    """A scorer whose objective is the distance of a number to 0; the coarse one is off by a constant."""

    def __init__(self, shift=0.0):
        self.shift, self.calls = shift, 0

    def score(self, rules):
        from neurosym_cli.synth.objective import Score

        self.calls += 1
        v = abs(rules[0]) + 1.0 + self.shift
        return Score(v, v, 0.0)

    def accept(self):
        pass


def test_patience_ends_stalled_phases_and_coarse_restarts_are_rescored_on_the_whole_data():
    from neurosym_cli.synth.mcmc import metropolis

    rng = random.Random(0)
    step = lambda r: ((r[0] + rng.choice((-1, 1)),), "shift")  # noqa: E731
    full = _Bowl()
    res = metropolis(lambda: (5,), step, full, steps=2000, restarts=2, final_fraction=0.2, temperature=0.01, rng=rng,
                     patience=50)
    assert res.best_score.total == 1.0 and set(res.stopped) == {"restart1", "restart2", "final"}
    assert sum(res.proposed.values()) < 600  # three phases, each stopped ~50 proposals after its optimum
    full, coarse = _Bowl(), _Bowl(shift=100.0)
    res = metropolis(lambda: (5,), step, full, steps=400, restarts=2, final_fraction=0.25, temperature=0.01,
                     rng=random.Random(1), coarse=coarse)
    assert coarse.calls > full.calls  # the restarts ran on the coarse scorer
    assert res.best_score.total == full.score(res.best).total  # the best is a whole-data score, never a coarse one


# --- the command ------------------------------------------------------------------------------------------------

def test_select_end_to_end_then_selected_true(tmp_path):
    """The paper's method (PAPER_METHOD), appendix B's selection: the pipeline of selected=true then runs the selected
    program itself (pipeline.select=front would run a pick among its front; tests/test_search_keys.py: hybrid)."""
    run(["train", "task=two-groups-cross", "budget=tiny", "threads=1"], tmp_path)
    p = run(["select", "task=two-groups-cross", "budget=tiny", "threads=1", "select.lam=[0.3,1.0]",
             "select.rules=[1,2]", "select.features=[v1]", "budget.val_seeds=3", "select.jobs=2",
             "select.finalists=2", *PAPER_METHOD], tmp_path, timeout=600)
    exp = tmp_path / "two-groups-cross/tiny/seed0"
    rec = json.loads((exp / "select/selected.json").read_text())
    sel = json.loads((exp / "select/selection.json").read_text())
    assert len(sel["programs"]) == 4 and rec["name"] in {r["name"] for r in sel["programs"]}
    assert "picked" in p.stdout and rec["name"] in p.stdout
    assert (exp / f"eval/prog-retrained-{rec['name']}/metrics.json").exists()
    finalists = [r for r in sel["retrained"]]
    assert 1 <= len(finalists) <= 2 and all(r["similar"] for r in sel["programs"] if r["name"] in
                                             {f["name"] for f in finalists})
    lines = (exp / "select/selection.csv").read_text().splitlines()
    assert len(lines) == 5 and "val_loss" in lines[0] and "picked" in lines[0]
    p = run(["pipeline", "task=two-groups-cross", "budget=tiny", "baselines=[prog-retrained]", "selected=true",
             *PAPER_METHOD], tmp_path)
    assert f"rules={rec['rules']} lam={rec['lam']:g}" in p.stdout and "already trained" in p.stdout + p.stderr
    assert f"prog-retrained-{rec['name']}" in p.stdout  # the results table names the selected program
    p = run(["show-program", "task=two-groups-cross", "budget=tiny", "selected=true", *PAPER_METHOD], tmp_path)
    assert "hall of fame by complexity" in p.stdout and "search's pick" in p.stdout


def test_selected_without_a_selection_is_one_line(tmp_path):
    p = run(["eval", "task=random-grid", "budget=tiny", "baseline=prog", "selected=true"], tmp_path, check=False)
    assert p.returncode == 1 and len(p.stderr.strip().splitlines()) == 1
    assert "neurosym select task=random-grid budget=tiny seed=0" in p.stderr


def test_no_test_episode_before_the_choice(tmp_path, monkeypatch):
    """Every test-seed evaluation happens after selected.json is written: no test episode can sway the pick."""
    import neurosym_cli.evaluation as evaluation
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.stages import RunInfo
    from neurosym_cli.stages.select import run_selection, selected_file
    from neurosym_cli.stages.train import train

    common = [f"runs_root={tmp_path}", "task=two-groups-cross", "budget=tiny", "budget.val_seeds=2"]
    train(compose_config("train", common), RunInfo())
    cfg = compose_config("select", common + ["select.lam=[0.5]", "select.rules=[1,2]", "select.features=[v1]",
                                             "select.jobs=1"])
    calls, real = [], evaluation.evaluate

    def spy(*a, split="test", **k):
        calls.append((split, selected_file(cfg).exists()))
        return real(*a, split=split, **k)

    import neurosym_cli.stages.evaluate as stage_eval

    monkeypatch.setattr(evaluation, "evaluate", spy)
    monkeypatch.setattr(stage_eval, "evaluate", spy)
    run_selection(cfg, RunInfo())
    assert {s for s, _ in calls} == {"val", "test"}
    assert all(written for s, written in calls if s == "test")
    assert not any(written for s, written in calls if s == "val")
