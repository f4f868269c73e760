"""The search settings that name a program (schemes/searched.SEARCH_VARIANTS) are one list: the program's tag, the
selection's record (select/selected.json), select's offer to reuse a sweep's programs and the result collectors
all read it, so a program of synth.search=hybrid is found again under its own name."""

import json

from neurosym_cli.schemes.searched import (SEARCH_KEYS, SEARCH_VARIANTS, program_tag, recorded_search,
                                           search_tag)

from test_cli import run


def test_every_setting_of_the_tag_is_recorded_by_select():
    assert SEARCH_KEYS == tuple(v.key for v in SEARCH_VARIANTS)
    assert "search" in SEARCH_KEYS  # the hybrid names its programs -hybrid


def test_program_tag_of_a_record_is_the_tag_of_its_config():
    from neurosym_cli.commands.apps import compose_config

    for extra in ([], ["synth.search=hybrid"], ["synth.objective=hinge", "synth.coarse=4", "synth.patience=50"],
                  ["synth.own_scores=false", "synth.simplify=false", "synth.search=hybrid"]):
        cfg = compose_config("synth", ["task=two-groups-cross", "budget=tiny", "lam=0.5", *extra])
        synth = {k: getattr(cfg.synth, k) for k in SEARCH_KEYS}
        assert program_tag(rules=cfg.rules, lam=cfg.lam, features=cfg.features, synth=synth) == search_tag(cfg)
    cfg = compose_config("synth", ["task=two-groups-cross", "budget=tiny", "lam=0.5", "synth.search=hybrid"])
    assert search_tag(cfg) == f"k{cfg.rules}-lam0.5-{cfg.features}-hybrid"


def test_a_record_written_before_a_setting_existed_reads_as_its_default():
    old = {"objective": "paper", "own_scores": True, "simplify": True, "coarse": 4, "patience": 500}  # no search
    assert recorded_search(old)["search"] == "mcmc"
    assert program_tag(rules=5, lam=0.3, features="v2", synth=old) == "k5-lam0.3-v2-coarse4-patience500"


def test_selected_true_finds_the_hybrid_program_it_selected(tmp_path):
    """select under synth.search=hybrid records the search; a later pipeline selected=true (no synth.search on its
    command line) runs the selected -hybrid program instead of searching another one with MCMC."""
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.stages.reuse import searched_otherwise
    from neurosym_cli.stages.select import grid

    run(["train", "task=two-groups-cross", "budget=tiny", "threads=1"], tmp_path)
    grid_args = ["select.lam=[0.5]", "select.rules=[1]", "select.features=[v1]"]
    run(["select", "task=two-groups-cross", "budget=tiny", "threads=1", *grid_args, "budget.val_seeds=2",
         "select.jobs=1", "select.finalists=1", "synth.search=hybrid"], tmp_path, timeout=600)
    exp = tmp_path / "two-groups-cross/tiny/seed0"
    rec = json.loads((exp / "select/selected.json").read_text())
    assert rec["synth"]["search"] == "hybrid" and rec["name"].endswith("-hybrid")

    # select under MCMC names the command that reuses the hybrid's programs (it did not see them before)
    cfg = compose_config("select", [f"runs_root={tmp_path}", "task=two-groups-cross", "budget=tiny", *grid_args,
                                    "synth.search=mcmc"])
    line = searched_otherwise(cfg, grid(cfg))
    assert line is not None and "synth.search=hybrid" in line

    p = run(["pipeline", "task=two-groups-cross", "budget=tiny", "threads=1", "baselines=[prog]", "selected=true",
             "pipeline.select=none"], tmp_path)  # the selected program as it is, not a pick among its front
    assert f"prog-{rec['name']}" in p.stdout
    programs = sorted(d.name for d in (exp / "synth").iterdir() if (d / "program.txt").exists())
    assert programs == [rec["name"]], programs  # no second program searched by MCMC


def _run_dir(exp, *, synth, tags, evaluated):
    """A run directory with one oracle manifest, a selection of ``synth``, program files ``tags`` and prog and
    prog-retrained evaluated at ``evaluated`` (rules 1, lam 0.5, features v1)."""
    (exp / "train/oracle").mkdir(parents=True)
    (exp / "train/oracle/manifest.json").write_text(json.dumps({"runtime": {}}))
    (exp / "select").mkdir()
    (exp / "select/selected.json").write_text(json.dumps({"rules": 1, "lam": 0.5, "features": "v1", "synth": synth}))
    (exp / "select/selection.json").write_text(json.dumps({"programs": []}))
    for tag in tags:
        (exp / "synth" / tag).mkdir(parents=True)
        (exp / "synth" / tag / "program.txt").write_text(f"program {tag}\n")
    for b in ("prog", "prog-retrained"):
        row = {"seed": 0, "cost": 1.0, "max_in": 1.0, "max_out": 1.0, "max_degree": 2.0, "mean_degree": 1.0,
               "collisions": 0.0}
        m = {"baseline": b, "label": f"{b}-{evaluated}", "seeds": 1, "seconds": 1.0, "per_seed": [row],
             "summary": {k: {"mean": v, "std": 0.0} for k, v in row.items() if k != "seed"},
             "config": {"rules": 1, "lam": 0.5, "features": "v1", "task": {"name": "random-cross", "lam": 0.5},
                        "synth": synth}}
        (exp / "eval" / m["label"]).mkdir(parents=True)
        (exp / "eval" / m["label"] / "metrics.json").write_text(json.dumps(m))


def test_the_collectors_keep_the_hybrid_program_and_not_another_search(tmp_path, monkeypatch):
    import benchmarks.results.collect as results_collect
    from benchmarks.run_seeds import collect

    hybrid = {"objective": "paper", "own_scores": True, "simplify": True, "coarse": 1, "patience": 0,
              "search": "hybrid"}
    exp = tmp_path / "random-cross/paper/seed0"
    _run_dir(exp, synth=hybrid, tags=["k1-lam0.5-v1-hybrid", "det-k1-lam0.5-v1-hybrid", "k1-lam0.5-v1"],
             evaluated="k1-lam0.5-v1-hybrid")
    res = collect(exp, "random-cross", 0, "paper", 1.0)
    assert sorted(res["programs"]) == ["det-k1-lam0.5-v1-hybrid", "k1-lam0.5-v1-hybrid"]

    monkeypatch.setattr(results_collect, "RESULTS", tmp_path / "results")
    monkeypatch.setattr(results_collect, "VARIANTS", {"random-cross": ("random-cross", None, "paper")})
    results_collect.collect(tmp_path, "paper", 0)
    out = json.loads((tmp_path / "results/random-cross.json").read_text())
    assert sorted(out["programs"]) == ["det-k1-lam0.5-v1-hybrid", "k1-lam0.5-v1-hybrid"]


def test_a_printed_command_composes_the_search_it_names():
    """Searched._line (the `create it with ...` hints) adds every search setting that differs from what a command
    line composes: synth.search=mcmc names no tag suffix, yet hybrid is the composed default."""
    import shlex

    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.schemes import get

    for task, extra in (("two-groups-cross", ["synth.search=mcmc"]), ("two-groups-cross", ["synth.objective=paper"]),
                        ("random-grid", ["synth.objective=scaled", "synth.search=mcmc", "synth.coarse=4"]),
                        ("random-grid", [])):
        cfg = compose_config("synth", [f"task={task}", "budget=tiny", "lam=0.5", *extra])
        line = get("prog-retrained").command("retrain", cfg)
        again = compose_config("retrain", shlex.split(line)[2:])
        assert {k: getattr(again.synth, k) for k in SEARCH_KEYS} == {k: getattr(cfg.synth, k) for k in SEARCH_KEYS}
        assert search_tag(again) == search_tag(cfg), line
