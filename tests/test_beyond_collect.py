"""benchmarks/beyond_paper.py's collector: a task-seed's result file holds the evaluation of the front's pick, not
another program's evaluation left in the run directory by an earlier front (vmas seed 2, 2026-12-04)."""

import json

from conftest import ROOT  # noqa: F401  (benchmarks/ importable from the repository root)


def _metrics(exp, label, baseline, cost):
    d = exp / "eval" / label
    d.mkdir(parents=True)
    rows = [{"seed": s, "cost": cost + 0.01 * s} for s in range(3)]
    d.joinpath("metrics.json").write_text(json.dumps({
        "baseline": baseline, "label": label, "summary": {"cost": {"mean": cost}, "max_degree": {"mean": 1.0}},
        "per_seed": rows, "seconds": 1.0}))


def test_the_collector_takes_the_picks_evaluation_and_not_a_stale_one(tmp_path):
    from benchmarks.beyond_paper import TASKS, collect, verdict

    exp = tmp_path / "run"
    stale, pick = "prog-retrained-file-k2-v1-near2-aaaa-v1", "prog-retrained-file-k2-v1-near1-bbbb-v1"
    _metrics(exp, stale, "prog-retrained", 5.0)  # sorts after the pick: a last-wins collector took it
    _metrics(exp, pick, "prog-retrained", 7.0)
    _metrics(exp, "prog-file-k2-v1-near1-bbbb-v1", "prog", 9.0)
    _metrics(exp, "tf-full", "tf-full", 6.0)
    _metrics(exp, "no-comm", "no-comm", 8.0)
    (exp / "select/front").mkdir(parents=True)
    (exp / "select/front/k2-v1.json").write_text(json.dumps({"picked": {"label": pick, "budget": 1.0}}))
    (exp / "train/oracle").mkdir(parents=True)
    (exp / "train/oracle/manifest.json").write_text(json.dumps({"runtime": {"cpu_kernels": "avx2"}}))
    res = collect(exp, TASKS["consensus"], 0, 1.0)
    assert sorted(res["baselines"]) == ["no-comm", "prog-retrained", "tf-full"]
    assert res["baselines"]["prog-retrained"]["label"] == pick
    assert verdict(res)["cost"]["prog-retrained"] == 7.0


def test_each_family_keeps_its_own_fronts_pick(tmp_path):
    """det-prog's front choice (select/front/det-<tag>.json, 'search': det-prog) filters det-prog's evaluations, and
    sorts before prog's: prog's choice is still the one that filters prog's."""
    from benchmarks.beyond_paper import TASKS, Suite, collect

    exp = tmp_path / "run"
    det_pick, det_stale = "det-prog-retrained-file-det-k2-v1-b2-cccc-v1", "det-prog-retrained-k2-lam0.5-v1"
    pick = "prog-retrained-file-k2-v1-b1-bbbb-v1"
    for label, baseline, cost in [(det_pick, "det-prog-retrained", 7.5), (det_stale, "det-prog-retrained", 4.0),
                                  ("det-prog-file-det-k2-v1-b2-cccc-v1", "det-prog", 9.5),
                                  ("det-prog-k2-lam0.5-v1", "det-prog", 2.5), (pick, "prog-retrained", 7.0),
                                  ("prog-retrained-file-k2-v1-b2-dddd-v1", "prog-retrained", 3.0),
                                  ("tf-full", "tf-full", 6.0), ("no-comm", "no-comm", 8.0)]:
        _metrics(exp, label, baseline, cost)
    (exp / "select/front").mkdir(parents=True)
    (exp / "select/front/k2-v1.json").write_text(json.dumps({"picked": {"label": pick}}))  # before 'search'
    (exp / "select/front/det-k2-v1.json").write_text(json.dumps({"search": "det-prog", "picked": {"label": det_pick}}))
    (exp / "train/oracle").mkdir(parents=True)
    (exp / "train/oracle/manifest.json").write_text(json.dumps({"runtime": {"cpu_kernels": "avx2"}}))
    res = collect(exp, TASKS["consensus"], 0, 1.0, suite=Suite(TASKS, tmp_path, None))  # every baseline
    labels = {b: e["label"] for b, e in res["baselines"].items()}
    assert labels["det-prog-retrained"] == det_pick and labels["det-prog"] == "det-prog-file-det-k2-v1-b2-cccc-v1"
    assert labels["prog-retrained"] == pick
    assert res["front_pick"]["picked"]["label"] == pick and res["det_front_pick"]["picked"]["label"] == det_pick


def _front(picked: str, means: dict) -> dict:
    """A front choice with tf-full at 100 and no-comm at 200 on validation, candidates at the given mean losses."""
    return {"picked": {"name": picked}, "retrain_rollouts": 50, "tf_full": {"loss": [99.0, 101.0]},
            "no_comm": {"loss": [199.0, 201.0]},
            "candidates": [{"name": n, "loss_mean": m, "degree": float(i), "excluded": False}
                           for i, (n, m) in enumerate(means.items())]}


def test_why_a_seed_misses_half_the_gap_is_read_from_the_fronts_validation():
    from benchmarks.beyond_paper import front_reach
    from benchmarks.results.beyond import _why_not_half

    reach = front_reach({"front_pick": _front("b1", {"b1": 160.0, "b2": 140.0, "near1": 190.0})})
    assert reach["best"] == "b2" and abs(reach["best_share"] - 0.6) < 1e-9 and reach["half"] == 150.0
    assert reach["loss_range"] == (140.0, 190.0) and reach["picked"] == "b1"
    assert front_reach({"front_pick": {}}) is None

    def seeds(missed: bool, front: dict) -> dict:
        return {"seeds": {0: {"holds": {"closes half the gap": not missed}, "gap_closed": 0.4}},
                "results": {0: {"front_pick": front}}}

    assert _why_not_half(seeds(False, _front("b1", {"b1": 140.0}))) == []  # the bar holds: nothing to explain
    picked_below = "\n".join(_why_not_half(seeds(True, _front("b1", {"b1": 160.0, "b2": 140.0}))))
    assert "half was within reach on validation, and the pick (b1)" in picked_below
    none_reach = "\n".join(_why_not_half(seeds(True, _front("b1", {"b1": 160.0, "b2": 170.0}))))
    assert "no candidate reached half" in none_reach and "closes 40% there" in none_reach


def test_a_control_against_silence_is_rendered_with_its_verdict(tmp_path, monkeypatch):
    import benchmarks.results.beyond as page

    (tmp_path / "controls").mkdir()
    rows = [{"program": "silent", "retrain_rollouts": 200, "cost": [150.0, 2.0], "max_in_out": 0.0, "gap_closed": 0.5,
             "text": "random(filter(d <= -1.0, l))", "minus_silent": None},
            {"program": "b1", "retrain_rollouts": 200, "cost": [149.0, 2.0], "max_in_out": 0.9, "gap_closed": 0.51,
             "text": "# a comment\nrandom(filter(d <= 1.0, l))", "minus_silent": [-1.0, 3.0]}]
    (tmp_path / "controls/swarm-200-seed1.json").write_text(json.dumps(
        {"seed": 1, "about": "A control.", "tf_full": 100.0, "no_comm": 200.0, "rows": rows}))
    monkeypatch.setattr(page, "OUT", tmp_path)
    text = "\n".join(page._control("swarm-200"))
    assert "| silent | 200 rollouts | 150.0 ± 2.0 | 0.00 | 50% |  |" in text  # 4 significant digits of tf-full's 100
    assert "| b1 | 200 rollouts | 149.0 ± 2.0 | 0.90 | 51% | −1.0 ± 3.0 |" in text
    assert "b1: `random(filter(d <= 1.0, l))`" in text  # the program's rules, not its comment
    assert "0 of the 1 program-and-length pairs beat silence" in text
    assert "closes 50% (200 rollouts) of the gap itself" in text and "is 1.0% of the gap" in text
    assert "almost all from retraining the oracle's weights" in text
    rows[1]["minus_silent"] = [-5.0, 3.0]
    (tmp_path / "controls/swarm-200-seed1.json").write_text(json.dumps(
        {"seed": 1, "about": "A control.", "tf_full": 100.0, "no_comm": 200.0, "rows": rows}))
    again = "\n".join(page._control("swarm-200"))
    assert "1 of the 1 program-and-length pairs beat silence retrained as long." in again
    rows[1]["minus_silent"] = [-30.0, 3.0]  # 30 % of the gap: the programs' own gain
    (tmp_path / "controls/swarm-200-seed1.json").write_text(json.dumps(
        {"seed": 1, "about": "A control.", "tf_full": 100.0, "no_comm": 200.0, "rows": rows}))
    assert "retraining the oracle" not in "\n".join(page._control("swarm-200"))
    assert page._control("consensus") == []
