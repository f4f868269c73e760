"""Training seeds of older and newer code combine when they made the same run: a config key a record predates reads
as what the code did then (seeds/read.as_run), so `neurosym report` over a runs root holding both does not refuse
them, and still refuses seeds that did differ."""

import copy
import json

import pytest

from neurosym_cli import seeds
from neurosym_cli.errors import ConfigError

OLD = {"task": {"name": "two-groups-cross", "lam": 0.5}, "budget": {"name": "tiny"}, "rules": 2, "lam": 0.5,
       "features": "v1", "synth": {"objective": "paper", "own_scores": True, "simplify": True, "coarse": 1,
                                   "patience": 0},
       "select": {"lam": [0.3, 0.5, 0.7, 1.0], "rules": [1, 2]}}
"""the shape of a record written before 2026-12-03 (no compile, synth.search, synth.front*, pipeline.select,
task.objective; select.lam spelled out)"""

NEW = copy.deepcopy(OLD)
NEW["task"]["objective"] = "paper"
NEW["compile"] = "auto"
NEW["pipeline"] = {"select": "none"}
NEW["synth"].update(search="mcmc", front=False, front_budgets=[], front_steps=0)
NEW["select"]["lam"] = []  # the grid of the objective (stages/select.LAM_GRIDS: paper's 0.3-1.0)
"""the same run as recorded today"""


def _metrics(root, seed, config, baseline="tf-full"):
    d = root / f"seed{seed}" / "eval" / baseline
    d.mkdir(parents=True)
    rows = [{"seed": 0, "cost": 1.0 + seed, **{m: 1.0 for m in seeds.METRICS if m != "cost"}}]
    (d / "metrics.json").write_text(json.dumps({"baseline": baseline, "label": baseline, "per_seed": rows,
                                                "summary": {}, "config": {**config, "seed": seed}}))


def _summarize(root):
    return seeds.summarize(seeds.from_runs_root(root), reps=200)


def test_an_old_record_beside_a_new_one_of_the_same_run_combines(tmp_path):
    _metrics(tmp_path, 0, OLD)
    _metrics(tmp_path, 1, NEW)
    assert _summarize(tmp_path).rows["tf-full"]["cost"]["n"] == 2


def test_compile_off_and_auto_are_both_the_eager_step_of_before(tmp_path):
    off = copy.deepcopy(NEW)
    off["compile"] = "off"
    _metrics(tmp_path, 0, OLD)
    _metrics(tmp_path, 1, NEW)
    _metrics(tmp_path, 2, off)
    assert _summarize(tmp_path).rows["tf-full"]["cost"]["n"] == 3


@pytest.mark.parametrize("key, value, shown", [
    (("synth", "search"), "hybrid", "hybrid"), (("synth", "front"), True, "true"), (("compile",), "on", "on"),
    (("pipeline", "select"), "front", "front"), (("task", "objective"), "scaled", "scaled"),
    (("select", "lam"), [0.5], "[0.5]")])
def test_an_old_record_beside_a_different_new_run_is_still_refused(tmp_path, key, value, shown):
    other = copy.deepcopy(NEW)
    d = other
    for k in key[:-1]:
        d = d[k]
    d[key[-1]] = value
    _metrics(tmp_path, 0, OLD)
    _metrics(tmp_path, 1, other)
    with pytest.raises(ConfigError, match=rf"^tf-full: {'.'.join(key)} differs across training seeds \(seed 0: "
                                          rf".*, seed 1: {shown.replace('[', '.').replace(']', '.')}\)"):
        _summarize(tmp_path)


def test_seed_files_with_and_without_the_search_setting_combine(tmp_path):
    from test_stats import seed_file

    costs = {"tf-full": [9.0, 11.0], "prog-retrained": [10.0, 12.0]}
    seed_file(tmp_path, "random-grid", 0, costs)  # selected.synth without search: MCMC
    new = seed_file(tmp_path, "random-grid", 1, costs)
    rec = json.loads(new.read_text())
    rec["selected"]["synth"]["search"] = "mcmc"
    new.write_text(json.dumps(rec))
    runs = seeds.from_seed_files(tmp_path.glob("*.json"))["random-grid"]
    assert seeds.summarize(runs, reps=200).rows["tf-full"]["cost"]["n"] == 2
    rec["selected"]["synth"]["search"] = "hybrid"
    new.write_text(json.dumps(rec))
    with pytest.raises(ConfigError, match=r"^synth.search differs across training seeds \(seed 0: mcmc, seed 1: "
                                          r"hybrid\)"):
        seeds.summarize(seeds.from_seed_files(tmp_path.glob("*.json"))["random-grid"])
