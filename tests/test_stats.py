"""The statistics of the results (neurosym_cli/stats.py) against hand-computed values, and the across-seed report
(neurosym_cli/seeds.py, `neurosym report`) on small hand-made seed files."""

import json
import math

import numpy as np
import pytest

from neurosym_cli import seeds, stats
from neurosym_cli.errors import ConfigError


# --- stats.py ---------------------------------------------------------------------------------------------------
def test_t_quantile_is_student_t_not_the_normal():
    assert stats.t95(2) == 12.706 and stats.t95(20) == 2.093 and stats.t95(31) == 2.042  # the printed table
    assert stats.t95(32) == pytest.approx(2.0395, abs=1e-4)  # t(0.975, 31 df), beyond the table
    assert stats.t95(101) == pytest.approx(1.9840, abs=1e-4)
    assert stats.t95(10_001) == pytest.approx(1.9602, abs=1e-4) and stats.t95(10_001) > 1.96
    with pytest.raises(ValueError):
        stats.t95(1)


def test_mean_ci_by_hand():
    m, h = stats.mean_ci([1.0, 2.0, 3.0, 4.0])
    sd = math.sqrt((1.5 ** 2 * 2 + 0.5 ** 2 * 2) / 3)  # 1.2910
    assert m == 2.5 and h == pytest.approx(3.182 * sd / 2)
    assert stats.mean_ci([5.0]) == (5.0, math.inf)  # no interval from one run


def test_interquartile_mean_is_the_25_percent_trimmed_mean():
    assert stats.iqm([8, 1, 7, 2, 6, 3, 5, 4]) == 4.5  # 1, 2 and 7, 8 cut: mean of 3..6
    assert stats.iqm([1.0, 2.0, 6.0]) == 3.0  # int(0.75) = 0 cut: the mean, as scipy's trim_mean
    assert stats.iqm([[1, 100], [2, 3], [4, 5], [6, 7]]) == 4.5  # over all runs and tasks: 100 is cut


def test_bootstrap_interval_is_stratified_by_task_and_seeded():
    # task 0 has runs 0 and 10, task 1 is 100 on both runs. Resampling within tasks, the flattened sample is
    # {a, b, 100, 100} with a, b in {0, 10}: IQM 50 (both 0, p = 1/4) or 55 (otherwise). Resampling across tasks
    # would reach 100 (all four 100).
    scores = [[0.0, 100.0], [10.0, 100.0]]
    point, lo, hi = stats.iqm_ci(scores, reps=20_000, seed=3)
    assert (point, lo, hi) == (55.0, 50.0, 55.0)
    assert stats.iqm_ci(scores, reps=2_000, seed=5) == stats.iqm_ci(scores, reps=2_000, seed=5)  # reproducible
    # two runs of one task: resampled means are 0, 5, 10 with p = 1/4, 1/2, 1/4: the 95 % interval is [0, 10]
    assert stats.iqm_ci([0.0, 10.0], reps=20_000) == (5.0, 0.0, 10.0)


def test_probability_of_improvement_by_hand():
    # losses, lower is better: pairs (x, y) with x < y count 1, ties 1/2: x=1: 3; x=2: 2 + 1/2; x=3: 1 + 1/2 -> 7/9
    assert stats.probability_of_improvement([1, 2, 3], [2, 3, 4]) == pytest.approx(7 / 9)
    # higher is better (rliable's own orientation): x=2 tie 1/2, x=3: 1 + 1/2 -> 2/9
    assert stats.probability_of_improvement([1, 2, 3], [2, 3, 4], lower_is_better=False) == pytest.approx(2 / 9)
    # averaged over tasks: the second task is won on every pair
    x, y = np.array([[1, 0], [2, 0], [3, 0]]), np.array([[2, 1], [3, 1], [4, 1]])
    assert stats.probability_of_improvement(x, y) == pytest.approx((7 / 9 + 1) / 2)
    assert stats.probability_of_improvement([1, 1], [1, 1]) == 0.5
    # x's runs {0, 10} against a constant y = 5: P = 1/2; resampled x gives 1, 1/2, 0 w.p. 1/4, 1/2, 1/4
    assert stats.improvement_ci([0.0, 10.0], [5.0, 5.0], reps=20_000) == (0.5, 0.0, 1.0)
    p, lo, hi = stats.improvement_ci([1.0, 2.0, 3.0], [7.0, 8.0, 9.0], reps=2_000)
    assert (p, lo, hi) == (1.0, 1.0, 1.0)  # separated samples: certain on every resample


def test_performance_profile_and_normalized_score():
    prof, lo, hi = stats.performance_profile(np.array([[0.2, 0.5], [0.9, 1.1]]), [0.0, 0.5, 1.0], reps=500)
    assert prof.tolist() == [1.0, 0.5, 0.25]  # strictly above tau, over all runs and tasks
    assert (lo <= prof).all() and (prof <= hi).all()
    prof, _, _ = stats.performance_profile([[0.2, 0.9], [1.1]], [0.5], reps=200)  # tasks with different run counts
    assert prof.tolist() == [pytest.approx(2 / 3)]
    assert stats.normalized_score(4.0, tf_full=2.0, no_comm=10.0) == 0.75  # 1 at tf-full, 0 at no-comm
    assert stats.normalized_score(2.0, 2.0, 10.0) == 1.0 and stats.normalized_score(10.0, 2.0, 10.0) == 0.0
    with pytest.raises(ValueError, match="not worse than tf-full"):
        stats.normalized_score(3.0, tf_full=5.0, no_comm=4.0)


def test_one_seed_has_no_interval():
    s = stats.across_seeds([3.0])
    assert s["n"] == 1 and s["mean"] == 3.0 and s["ci95"] is None and s["iqm_lo"] is None and s["std"] is None
    s = stats.across_seeds([1.0, 3.0], reps=1000)
    assert s["ci95"] == pytest.approx(12.706) and (s["iqm_lo"], s["iqm_hi"]) == (1.0, 3.0)


def test_metric_names_match_the_rollout():
    from neurosym_cli.rollout import METRICS

    assert seeds.SHARED == METRICS  # and seeds.METRICS adds the paper tasks' own (collisions)


# --- seeds.py: across-seed report on hand-made seed files --------------------------------------------------------
def seed_file(path, task, seed, costs, budget="tiny", pick=None, grid=((0.5, 2, "v1"),), machine=None):
    """A seed file in benchmarks/run_seeds.py's format: per baseline two evaluation seeds with the given losses."""
    rows = lambda c, deg: [{"seed": s, "episodes": 1, "cost": x, "max_in": deg, "max_out": deg,
                            "max_degree": 2 * deg, "mean_degree": deg, "collisions": 0.0} for s, x in enumerate(c)]
    baselines = {b: {"label": b, "summary": {}, "per_seed": rows(c, 0.0 if b == "no-comm" else 2.0), "seconds": 1}
                 for b, c in costs.items()}
    rec = {"task": task, "seed": seed, "budget": budget, "pick": pick or {"rules": 2, "lam": 0.5, "features": "v1"},
           "selected": {"val_seeds": 10, "synth": {"objective": "paper"}},
           "selection": [{"lam": lam, "rules": k, "features": f} for lam, k, f in grid],
           "baselines": baselines, "machine": machine or {"cpu_kernels": "avx2"}}
    f = path / f"{task}-seed{seed}.json"
    f.write_text(json.dumps(rec))
    return f


def three_seeds(tmp_path):
    # per training seed (mean over its two evaluation seeds): tf-full 10, 11, 12; prog-retrained 10.5, 11.5, 13;
    # no-comm 20, 21, 22
    for s, (tf, pr, nc) in enumerate([(10, 10.5, 20), (11, 11.5, 21), (12, 13, 22)]):
        seed_file(tmp_path, "random-grid", s, {"tf-full": [tf - 1, tf + 1], "prog-retrained": [pr, pr],
                                               "no-comm": [nc - 0.5, nc + 0.5]}, pick={"rules": 2 + s % 2, "lam": 0.5,
                                                                                      "features": "v1"})
    return seeds.from_seed_files(sorted(tmp_path.glob("*.json")))


def test_across_seed_summary_by_hand(tmp_path):
    by_task = three_seeds(tmp_path)
    s = seeds.summarize(by_task["random-grid"], reps=5000)  # picks differ (K 2, 3, 2): the method's outcome
    tf = s.rows["tf-full"]["cost"]
    assert tf["n"] == 3 and tf["mean"] == 11.0 and tf["ci95"] == pytest.approx(4.303 * 1.0 / math.sqrt(3))
    assert tf["iqm"] == 11.0 and tf["iqm_lo"] == 10.0 and tf["iqm_hi"] == 12.0
    pr = s.rows["prog-retrained"]["cost"]
    assert pr["mean"] == pytest.approx(35 / 3)
    poi = {r["y"]: r for r in s.improvement}
    assert list(poi)[:2] == ["tf-full", "no-comm"]  # the named comparisons first
    # prog-retrained {10.5, 11.5, 13} vs tf-full {10, 11, 12}: wins 10.5<11, 10.5<12, 11.5<12 -> 3/9
    assert poi["tf-full"]["p"] == pytest.approx(3 / 9) and poi["no-comm"]["p"] == 1.0
    assert poi["tf-full"]["lo"] <= 1 / 3 <= poi["tf-full"]["hi"] and poi["no-comm"]["lo"] == 1.0
    norm, left = seeds.normalized(by_task)
    assert left == [] and norm["prog-retrained"][0] == pytest.approx([0.95, 0.95, 0.9])  # (20-10.5)/(20-10), ...


def test_seed_files_of_before_and_after_mkls_intel_path_do_not_mix(tmp_path):
    """A seed file of before 2026-12-03 (no mkl_path: avx2 then left MKL its vendor path, now avx2-vendor) and one
    of today's avx2 were computed differently on AMD machines: the report refuses to mix them, naming the key."""
    costs = {"tf-full": [9.0, 11.0], "prog-retrained": [10.0, 12.0]}
    old = seed_file(tmp_path, "random-grid", 0, costs)
    new = seed_file(tmp_path, "random-grid", 1, costs, machine={"cpu_kernels": "avx2", "mkl_path": "intel"})
    assert seeds.from_seed_file(old).settings["cpu_kernels"] == "avx2-vendor"
    assert seeds.from_seed_file(new).settings["cpu_kernels"] == "avx2"
    resumed = tmp_path / "other"
    resumed.mkdir()  # an oracle manifest of before the change, collected after it: mkl_path recorded as None
    f = seed_file(resumed, "random-grid", 0, costs, machine={"cpu_kernels": "avx2", "mkl_path": None})
    assert seeds.from_seed_file(f).settings["cpu_kernels"] == "avx2-vendor"
    with pytest.raises(ConfigError, match="^cpu_kernels differs across training seeds"):
        seeds.summarize(seeds.from_seed_files(tmp_path.glob("*.json"))["random-grid"])


def test_a_single_seed_is_reported_as_such(tmp_path):
    seed_file(tmp_path, "random-grid", 0, {"tf-full": [9.0, 11.0], "prog-retrained": [10.0, 12.0]})
    s = seeds.summarize(seeds.from_seed_files(tmp_path.glob("*.json"))["random-grid"])
    m = s.rows["tf-full"]["cost"]
    assert m["n"] == 1 and m["ci95"] is None and m["iqm_lo"] is None
    assert m["eval_ci95"] == pytest.approx(12.706)  # what it has: the interval over its two evaluation seeds
    assert seeds.fmt_mean(m) == "10.00 (1 seed)" and seeds.fmt_iqm(m) == "-"
    assert "1 training seed" in seeds.caption(1) and "no interval across one training seed" in seeds.caption(1)
    assert s.improvement[0]["lo"] is None and "no interval" in seeds.fmt_p(s.improvement[0])


def test_mixed_settings_refuse_in_one_line_naming_the_key(tmp_path):
    seed_file(tmp_path, "random-grid", 0, {"tf-full": [1.0, 2.0]})
    seed_file(tmp_path, "random-grid", 1, {"tf-full": [1.0, 2.0]}, budget="quick")
    runs = seeds.from_seed_files(tmp_path.glob("*.json"))["random-grid"]
    with pytest.raises(ConfigError) as e:
        seeds.summarize(runs)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("budget differs") and "report.mix=true" in msg
    assert "seed 0: tiny" in msg and "seed 1: quick" in msg
    s = seeds.summarize(runs, mix=True, reps=500)  # asked to mix: reported, saying what differs
    assert s.notes and s.notes[0].startswith("budget differs") and s.rows["tf-full"]["cost"]["n"] == 2
    seed_file(tmp_path, "random-grid", 1, {"tf-full": [1.0, 2.0]}, grid=((0.5, 2, "v1"), (0.7, 2, "v1")))
    with pytest.raises(ConfigError, match="^select.grid differs"):
        seeds.summarize(seeds.from_seed_files(tmp_path.glob("*.json"))["random-grid"])


def test_run_directories_with_different_k_refuse_unless_picked_by_select(tmp_path):
    def metrics(seed, rules, selected=False):
        d = tmp_path / f"seed{seed}" / "eval" / f"prog-k{rules}"
        d.mkdir(parents=True)
        rows = [{"seed": 0, "cost": 1.0 + seed, **{m: 1.0 for m in seeds.METRICS if m != "cost"}}]
        cfg = {"seed": seed, "rules": rules, "lam": 0.5, "features": "v1", "selected": selected,
               "task": {"name": "random-grid"}, "budget": {"name": "tiny"}, "exp_dir": str(d.parents[1])}
        (d / "metrics.json").write_text(json.dumps({"baseline": "prog", "label": f"prog-k{rules}", "per_seed": rows,
                                                    "config": cfg, "summary": {}}))

    metrics(0, 2)
    metrics(1, 3)
    runs = seeds.from_runs_root(tmp_path)
    assert [r.seed for r in runs] == [0, 1] and set(runs[0].entries) == {"prog"}
    with pytest.raises(ConfigError, match=r"^prog: rules differs across training seeds \(seed 0: 2, seed 1: 3\)"):
        seeds.summarize(runs)
    for f in tmp_path.glob("seed*/eval/*/metrics.json"):  # the same K values, each picked by `neurosym select`
        m = json.loads(f.read_text())
        m["config"]["selected"] = True
        f.write_text(json.dumps(m))
    assert seeds.summarize(seeds.from_runs_root(tmp_path), reps=500).rows["prog"]["cost"]["n"] == 2


def test_marl_eval_layout(tmp_path):
    by_task = three_seeds(tmp_path)
    d = seeds.marl_eval(by_task)
    runs = d["neurosym"]["random-grid"]["prog-retrained"]
    assert list(d) == ["neurosym"] and list(runs) == ["seed0", "seed1", "seed2"]
    run = runs["seed1"]
    assert set(run) == {"step_1", "absolute_metrics"}
    assert run["step_1"]["step_count"] == 8  # conf/budget/tiny.yaml's train_rollouts
    assert run["absolute_metrics"]["cost"] == [11.5, 11.5] and run["step_1"]["cost"] == [11.5, 11.5]
    assert set(run["absolute_metrics"]) == set(seeds.METRICS)


# --- `neurosym report` over seed files (the console script) -------------------------------------------------------
def test_report_over_seed_files_writes_csv_and_marl_eval_json_and_refuses_mixed_settings(tmp_path):
    import csv

    from test_cli import run

    files = tmp_path / "seeds"
    files.mkdir()
    three_seeds(files)
    p = run(["report", f"report.seed_files={files}", "report.reps=2000"], tmp_path)
    words = " ".join(p.stdout.replace("│", " ").split())
    assert "random-grid: 3 training seeds (0, 1, 2)" in words
    assert "mean ± 95 % Student-t interval across training seeds (2 degrees of freedom)" in words
    assert "probability of improvement" in words
    out = files / "report"
    rows = list(csv.DictReader(open(out / "report.csv")))
    tf = next(r for r in rows if r["baseline"] == "tf-full" and r["metric"] == "cost")
    assert tf["train_seeds"] == "3" and float(tf["mean"]) == 11.0 and float(tf["iqm_lo"]) == 10.0
    assert float(tf["ci95_half"]) == pytest.approx(4.303 / math.sqrt(3))
    poi = list(csv.DictReader(open(out / "improvement.csv")))
    assert poi[0]["x"] == "prog-retrained" and poi[0]["y"] == "tf-full"
    assert float(poi[0]["p_x_improves_on_y"]) == pytest.approx(1 / 3)
    marl = json.loads((out / "report_marl_eval.json").read_text())
    assert set(marl["neurosym"]["random-grid"]["tf-full"]["seed2"]) == {"step_1", "absolute_metrics"}
    rep = json.loads((out / "report.json").read_text())
    assert rep["tasks"]["random-grid"]["baselines"]["tf-full"]["train_seeds"] == 3
    assert not list(files.glob("*.png")) and not list(out.glob("*.png"))  # plots=false: nothing drawn
    seed_file(files, "random-grid", 1, {"tf-full": [1.0, 2.0]}, budget="quick")
    p = run(["report", f"report.seed_files={files}"], tmp_path, check=False)
    err = p.stderr.strip().splitlines()
    assert p.returncode != 0 and len(err) == 1 and "budget differs across training seeds" in err[0], p.stderr
    assert "report.mix=true" in err[0]
    p = run(["report", f"report.seed_files={files}", "report.mix=true", "report.reps=500"], tmp_path)
    assert "mixed (report.mix=true): budget differs" in " ".join(p.stdout.split())
