"""The policy's formats (export.formats): policy.pt2 (torch.export) loads with torch.export.load and equals the eager
policy on the golden inputs and on another team size and K (its sizes are free); ONNX by the dynamo exporter runs in
onnxruntime and matches; --check reports each format on its own line; a format whose package is missing or whose
exporter fails is one line and the others are written and checked; naming that format in export.formats makes it
fail the command. One tiny training, a one-rule program file (K = 1: the examples are padded), seconds each."""

import importlib.util
import json
import os
import sys

import numpy as np
import pytest
import torch

import neurosym as ns

pytestmark = pytest.mark.skipif(importlib.util.find_spec("onnx") is None,
                                reason="the onnx extra is not installed (pip install -e '.[onnx]')")

PROGRAM = "argmax(map(-1.0*d, filter(true, l)))\n"  # one rule: K = 1


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """make(**overrides) -> an export config of random-cross's one-rule program over an oracle trained once."""
    root = tmp_path_factory.mktemp("formats")
    prog = root / "one-rule.txt"
    prog.write_text(PROGRAM)
    base = {"runs_root": str(root / "runs"), "threads": 1, "plots": False}
    ns.train(ns.compose("train", base, task="random-cross", budget="tiny"), "tf-full")

    def make(name, **over):
        return ns.compose("export", {**base, "program": str(prog), "export.dir": str(root / name), **over},
                          task="random-cross", budget="tiny", baseline="prog")

    return make


def _golden(folder):
    with np.load(os.path.join(folder, "golden.npz")) as z:
        return {k: torch.from_numpy(z[k]) for k in z.files}


def _eager(cfg):
    """The policy as evaluation runs it, with the task's target: the function every format must equal."""
    from neurosym_cli.export.policy import TeamPolicy
    from neurosym_cli.run.models import load_baseline
    from neurosym_cli.tasks.base import applied_action

    policy, task, _ = load_baseline(cfg, torch.device("cpu"))
    return TeamPolicy(policy.eval(), applied_action(task)).eval()


def _status(report):
    return {r["file"]: r["status"] for r in report["results"]}


def test_pt2_round_trip_equals_the_eager_policy_with_free_team_size(trained):
    cfg = trained("pt2", **{"export.formats": ["pt2"]})
    out = ns.export(cfg)
    assert set(out["formats"]) == {"pt2"} and "policy.pt" not in out["files"] and "policy.onnx" not in out["files"]
    g, eager = _golden(out["folder"]), _eager(cfg)
    m = torch.export.load(os.path.join(out["folder"], "policy.pt2")).module()
    assert g["e0_picks"].shape[-1] == 1  # traced at K = 1 padded to 2: K is still free
    with torch.no_grad():
        for e in range(3):
            args = (g[f"e{e}_agent"], g[f"e{e}_rel"], g[f"e{e}_picks"])
            got, want = m(*args)[0], eager(*args)[0]
            assert torch.allclose(got, want, atol=1e-6) and torch.allclose(got, g[f"e{e}_action"], atol=1e-5)
        n = 6  # another team size and three picks per agent, one of them nobody
        picks = torch.stack([torch.arange(n).roll(s) for s in (1, 2)], -1).view(1, 1, n, 2).expand(4, 1, n, 2)
        picks = torch.cat([picks, torch.full((4, 1, n, 1), -1)], -1)
        args = (g["e0_agent"][:4, :n], g["e0_rel"][:4, :n, :n], picks)
        assert torch.allclose(m(*args)[0], eager(*args)[0], atol=1e-6)
    made = json.load(open(os.path.join(out["folder"], "manifest.json")))["formats"]["pt2"]
    assert made["exporter"].startswith("torch.export.export") and made["free"] == "B, N, K in [1, 15]"
    report = ns.export(cfg, check=True)
    assert _status(report) == {"program.py": "ok", "program.json": "ok", "program.h": _status(report)["program.h"],
                               "policy.pt2": "ok", "checksums": "ok"}, report["results"]


def test_every_format_by_default_dynamo_onnx_matches_and_the_check_has_a_line_each(trained):
    ort = pytest.importorskip("onnxruntime", reason="the dynamo ONNX file is run by onnxruntime (the onnx extra)")
    pytest.importorskip("onnxscript", reason="the dynamo exporter needs onnxscript (the onnx extra)")
    cfg = trained("all")
    out = ns.export(cfg)
    made = out["formats"]
    assert list(made) == ["torchscript", "pt2", "onnx"] and not any("skipped" in v for v in made.values())
    assert "dynamo=True" in made["onnx"]["exporter"] and made["onnx"]["opset"] == 18
    assert "torch.jit.trace" in made["torchscript"]["exporter"]
    g, eager = _golden(out["folder"]), _eager(cfg)
    s = ort.InferenceSession(os.path.join(out["folder"], "policy.onnx"), providers=["CPUExecutionProvider"])
    for e in range(3):
        args = (g[f"e{e}_agent"], g[f"e{e}_rel"], g[f"e{e}_picks"])
        got = s.run(None, {"agent": args[0].numpy(), "rel": args[1].numpy(), "picks": args[2].numpy()})[0]
        with torch.no_grad():
            assert np.abs(got - eager(*args)[0].numpy()).max() < 1e-5
    from neurosym_cli.export.policy import policy_graphs  # each piece on random inputs (x apart from h, ...)

    team = _eager(cfg)
    gen = torch.Generator().manual_seed(0)
    for piece in policy_graphs(team.policy, team.target, g["e0_agent"], g["e0_rel"], g["e0_picks"])[1]:
        args = [torch.randn(a.shape, generator=gen) if a.is_floating_point() else a for a in piece.args]
        s = ort.InferenceSession(os.path.join(out["folder"], f"{piece.file}.onnx"), providers=["CPUExecutionProvider"])
        feeds = {i.name: args[list(piece.inputs).index(i.name)].numpy() for i in s.get_inputs()}
        with torch.no_grad():
            want = piece.module(*args)
        want = want[0] if isinstance(want, tuple) else want  # act: (action, raw)
        assert np.abs(s.run(None, feeds)[0] - want.numpy()).max() < 1e-5, piece.file
    report = ns.export(cfg, check=True)
    status = _status(report)
    for name in ("policy.pt", "policy.pt2", "policy.onnx", "agent/*.onnx"):
        assert status[name] == "ok", report["results"]
    assert [r["file"] for r in report["results"]].count("policy.pt2") == 1
    readme = open(os.path.join(out["folder"], "README.md")).read()
    assert "torch.export.load(\"policy.pt2\")" in readme and "torch::jit::load" in readme and "Ort::Session" in readme


def test_a_missing_package_is_one_line_and_the_other_formats_are_written_and_checked(trained, monkeypatch):
    monkeypatch.setitem(sys.modules, "onnxscript", None)  # `import onnxscript` fails, as when not installed
    cfg = trained("no-onnxscript")
    out = ns.export(cfg)  # every format by default: the one that cannot be written is skipped
    why = out["formats"]["onnx"]["skipped"]
    assert why.startswith("onnxscript is not installed") and 'pip install -e ".[onnx]"' in why
    assert {"policy.pt", "policy.pt2"} <= set(out["files"]) and "policy.onnx" not in out["files"]
    assert not os.path.exists(os.path.join(out["folder"], "agent"))
    report = ns.export(cfg, check=True)
    line = next(r for r in report["results"] if r["file"] == "policy.onnx")
    assert line["status"] == "skipped" and "not written by the export: onnxscript is not installed" in line["detail"]
    assert _status(report)["policy.pt"] == _status(report)["policy.pt2"] == "ok"
    with pytest.raises(ns.UserError, match=r"policy.onnx: required \(onnx\) but not written by the export"):
        ns.export(trained("no-onnxscript", **{"export.formats": ["onnx"]}), check=True)
    asked = trained("asked-onnx", **{"export.formats": ["pt2", "onnx"]})
    with pytest.raises(ns.UserError, match=r"names onnx, which was not written \(onnxscript is not installed"):
        ns.export(asked)
    assert os.path.exists(os.path.join(asked.export.dir, "policy.pt2"))  # the rest is written
    legacy = ns.export(trained("legacy", **{"export.onnx": "legacy"}))  # the legacy exporter needs no onnxscript
    assert "legacy" in legacy["formats"]["onnx"]["exporter"] and legacy["formats"]["onnx"]["opset"] == 17


def test_an_exporter_that_fails_costs_its_format_only_and_a_broken_file_fails_the_check(trained, monkeypatch):
    def boom(*a, **k):
        raise RuntimeError("the exporter broke\nsecond line")

    monkeypatch.setattr(torch.export, "export", boom)
    cfg = trained("broken", **{"export.onnx": "legacy"})
    out = ns.export(cfg)
    assert out["formats"]["pt2"] == {"files": [], "skipped": "its exporter failed: RuntimeError: the exporter broke"}
    assert {"policy.pt", "policy.onnx"} <= set(out["files"])
    report = ns.export(cfg, check=True)
    assert _status(report)["policy.pt2"] == "skipped" and report["first_mismatch"] is None
    with pytest.raises(ns.UserError, match=r"names pt2, which was not written \(its exporter failed"):
        ns.export(trained("broken-asked", **{"export.formats": ["torchscript", "pt2"]}))
    monkeypatch.undo()
    with open(os.path.join(out["folder"], "policy.pt"), "r+b") as f:  # a broken file: a mismatch, not a skip
        f.seek(40)
        f.write(b"\0" * 64)
    from neurosym_cli.export.check import run_check

    report = run_check(out["folder"])
    assert _status(report)["policy.pt"] == "mismatch" and report["exit"] == 1


def test_an_unknown_format_or_exporter_is_one_line():
    for over, words in (({"export.formats": ["pt3"]}, "unknown format 'pt3'; choose among torchscript, pt2, onnx"),
                        ({"export.onnx": "fast"}, "export.onnx must be one of dynamo, legacy")):
        with pytest.raises(ns.ConfigError, match=words):
            ns.compose("export", over, task="random-cross", budget="tiny")


def test_the_export_command_prints_its_own_lines_not_the_exporters_chatter(tmp_path):
    """onnxscript and onnx_ir log ~80 INFO lines per dynamo export; the console shows neurosym's and Hydra's INFO
    lines only, other libraries' from WARNING on (conf/hydra/job_logging/rich.yaml)."""
    pytest.importorskip("onnxscript", reason="the dynamo exporter needs onnxscript (the onnx extra)")
    from test_cli import run

    run(["train", "task=random-grid", "budget=tiny", "threads=1"], tmp_path)
    p = run(["export", "task=random-grid", "budget=tiny", "threads=1", "baseline=tf-full",
             "export.formats=[onnx]"], tmp_path)
    said = p.stdout + p.stderr
    assert "exported tf-full" in said and "neurosym export:" in said
    assert "constant folding" not in said and "unused nodes" not in said, said
    assert len(said.splitlines()) < 20, said
