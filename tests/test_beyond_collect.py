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
