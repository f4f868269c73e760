"""`neurosym export` and its check: for every paper task and the example plugin task, each with one program kind
(both kinds twice over the five), export then check in a process that cannot import neurosym (picks identical, actions within tolerance); the check fails
on a corrupted folder naming the first mismatch; a baseline without a program exports the policy alone; the
one-line refusals; the decentralised runtime example matches the evaluation's loss. Each task is trained once
per module, at the tiny budget."""

import importlib.util
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
import torch

import neurosym as ns
from conftest import ROOT, neurosym_cmd

pytestmark = pytest.mark.skipif(importlib.util.find_spec("onnxruntime") is None
                                or importlib.util.find_spec("onnx") is None,
                                reason="the onnx extra is not installed (pip install -e '.[onnx]')")

RING = ROOT / "examples" / "ring" / "conf"
TASKS = {"random-cross": None, "random-grid": None, "unlabeled-goals": None, "two-groups-cross": None, "ring": RING}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """task -> its config, its oracle trained once (tiny budget) in a module's runs root."""
    root = tmp_path_factory.mktemp("export-runs")
    made = {}

    def get(task):
        if task not in made:
            cfg = ns.compose("export", {"runs_root": str(root), "threads": 1, "plots": False}, task=task,
                             budget="tiny", config_dir=TASKS[task])
            ns.train(cfg, "tf-full")
            made[task] = cfg
        return made[task]

    return get


_EXPORTS: dict = {}


def exported(runs, task, kind, program=True):
    """(config, what export wrote) of one task and baseline, synthesized (for a program) and exported once per module."""
    cfg = runs(task)
    key = (cfg.runs_root, task, kind)
    if key not in _EXPORTS:
        if program:
            ns.synth(cfg, kind)
        _EXPORTS[key] = ns.export(cfg, kind)
    return cfg, _EXPORTS[key]


# each task once and each program kind on two or three tasks: the check's code paths are per kind and per feature
# map, and the other tests export random-cross's det-prog and unlabeled-goals' and two-groups-cross's prog too
CASES = [("random-cross", "prog"), ("random-grid", "det-prog"), ("unlabeled-goals", "det-prog"),
         ("two-groups-cross", "prog"), ("ring", "det-prog")]


@pytest.mark.parametrize("task,kind", CASES)
def test_export_then_check_passes_without_neurosym(runs, task, kind):
    cfg, out = exported(runs, task, kind)
    assert out["program"] and out["policy"]
    report = ns.export(cfg, kind, check=True)
    assert report["neurosym_importable"] is False and report["first_mismatch"] is None
    status = {r["file"]: r["status"] for r in report["results"]}
    want_c = "ok" if shutil.which("cc") else "skipped"
    assert status == {"program.py": "ok", "program.json": "ok", "program.h": want_c, "policy.onnx": "ok",
                      "policy.pt": "ok", "policy.pt2": "ok", "agent/*.onnx": "ok",
                      "checksums": "ok"}, report["results"]
    folder = out["folder"]
    prog = json.loads(open(f"{folder}/program.json").read())
    assert len(prog["rounds"]) == cfg.task.rounds  # unlabeled-goals: one program per round
    assert prog["semantics"] == "neurosym-rules/1" and all(f["unit"] is not None for f in prog["features"])
    if kind == "det-prog":
        assert all(r["kind"] == "argmax" for rs in prog["rounds"] for r in rs)


def test_the_exported_code_reads_like_the_program(runs):
    """One function per rule with the rule's text above it, features named, in Python and in C."""
    cfg, out = exported(runs, "two-groups-cross", "prog")
    text = ns.parse(json.loads(open(f"{out['folder']}/program.json").read())["text"])
    from neurosym_cli.dsl.printer import rule_text

    py = open(f"{out['folder']}/program.py").read()
    c = open(f"{out['folder']}/program.h").read()
    for k, rule in enumerate(text.rounds[0], start=1):
        assert f"# {rule_text(rule)}\ndef round1_rule{k}(" in py
        assert f"/* {rule_text(rule)} */" in c and f"ns_round1_rule{k}(" in c
    for name in text.features():
        assert f"def feature_{name}(me, o):" in py and f"ns_feature_{name}(" in c
    assert "import math" in py and "neurosym_cli" not in py.replace("exported by neurosym", "")


def test_a_corrupted_golden_pick_fails_naming_the_first_mismatch(runs, tmp_path):
    cfg, out = exported(runs, "random-cross", "prog")
    bad = tmp_path / "bad"
    shutil.copytree(out["folder"], bad)
    with np.load(bad / "golden.npz") as z:
        arrays = {k: z[k] for k in z.files}
    p = arrays["e1_picks"]
    p[2, 0, 3, 0] = (p[2, 0, 3, 0] + 1) % p.shape[2]  # episode 1, step 2, round 1, agent 3
    np.savez_compressed(bad / "golden.npz", **arrays)
    from neurosym_cli.export.check import run_check

    report = run_check(bad)
    assert report["exit"] == 1
    assert report["first_mismatch"].startswith("program.py: episode 1, step 2, round 1, agent 3: picks"), report
    with pytest.raises(ns.UserError, match="program.py: episode 1, step 2, round 1, agent 3"):
        ns.export(ns.compose("export", {"runs_root": cfg.runs_root, "export.dir": str(bad)}, task="random-cross",
                             budget="tiny"), "prog", check=True)


def test_a_baseline_without_a_program_exports_the_policy_alone(runs):
    cfg, out = exported(runs, "random-grid", "tf-full", program=False)
    assert not out["program"] and out["policy"]
    names = set(out["files"])
    assert "program.py" not in names and {"policy.onnx", "policy.pt", "policy.pt2", "golden.npz"} <= names
    report = ns.export(cfg, "tf-full", check=True)
    assert [r["file"] for r in report["results"]] == ["policy.pt", "policy.pt2", "policy.onnx", "agent/*.onnx",
                                                      "checksums"]
    assert all(r["status"] == "ok" for r in report["results"])


def test_the_command_line_refuses_an_existing_folder_and_checks_with_the_flag(runs):
    cfg, out = exported(runs, "random-cross", "det-prog")
    env = {**os.environ, "NEUROSYM_RUNS": cfg.runs_root}
    args = [*neurosym_cmd(), "export", "task=random-cross", "budget=tiny", "baseline=det-prog", "threads=1"]
    p = subprocess.run(args, capture_output=True, text=True, env=env, timeout=300)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode != 0 and len(lines) == 1 and "overwrite=true" in lines[0], p.stderr
    p = subprocess.run([*args, "--check"], capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 0 and "export check passed" in p.stdout, p.stdout + p.stderr


def test_the_decentralised_runtime_matches_the_evaluation_loss(runs):
    cfg, out = exported(runs, "unlabeled-goals", "prog")  # two rounds, random rules, the goal softmax inside
    p = subprocess.run([sys.executable, str(ROOT / "examples" / "deploy" / "runtime.py"), out["folder"], "--episode",
                        "1", "task=unlabeled-goals", "budget=tiny"], capture_output=True, text=True, timeout=300,
                       env={**os.environ, "NEUROSYM_RUNS": cfg.runs_root})
    assert p.returncode == 0 and "match" in p.stdout, p.stdout + p.stderr


def test_a_program_file_without_a_trained_model_exports_the_program_alone(tmp_path):
    prog = tmp_path / "mine.txt"
    prog.write_text("argmax(map(-1.0*d, filter(gd >= 0.5, l)))\nrandom(filter(d <= 3.0, l))\n")
    cfg = ns.compose("export", {"runs_root": str(tmp_path / "runs"), "program": str(prog)}, task="random-cross",
                     budget="tiny", baseline="prog")
    out = ns.export(cfg)
    assert out["program"] and not out["policy"]
    report = ns.export(cfg, check=True)
    assert {r["file"] for r in report["results"]} == {"program.py", "program.json", "program.h", "checksums"}
    assert report["first_mismatch"] is None


def test_a_feature_without_a_source_cannot_be_exported():
    from neurosym_cli.dsl.vocabulary import Feature, FeatureSet
    from neurosym_cli.export.spec import used_features

    vocab = FeatureSet((Feature("d", "other", "its distance", "m"), ))
    with pytest.raises(ns.ConfigError, match="feature 'd' of task t has no source"):
        used_features(ns.parse("argmax(map(d, filter(true, l)))\n"), vocab, "t")


def test_the_traced_dedup_is_the_loop_dedup():
    from neurosym_cli.dsl.interpret import dedup_valid, dedup_valid_traced

    g = torch.Generator().manual_seed(0)
    for k in range(1, 6):
        p = torch.randint(-1, 4, (50, 7, k), generator=g)
        assert torch.equal(dedup_valid(p), dedup_valid_traced(p))
