"""`neurosym export` keeps its promises under hostile use (docs/reliability.md, "Export"): it only ever replaces
an export (never a run directory or a user's folder, even with overwrite=true), two exports into one folder at
once do not both report success, the check fails what it did not check (an edited program.json, a golden file
without episodes, nothing replayed, an infinite tolerance), and the check works with a relative runs root (a
missing onnx extra: tests/test_export_formats.py). Program-file exports (no training) keep every test a few
seconds."""

import json
import os
import subprocess
import sys

import pytest

import neurosym as ns
from conftest import neurosym_cmd

PROGRAM = "argmax(map(-1.0*d, filter(gd >= 0.5, l)))\nrandom(filter(d <= 3.0, l))\n"


@pytest.fixture
def prog_cfg(tmp_path):
    """(config of a program-file export of random-cross, runs root): nothing trained, so it exports the program
    alone."""
    prog = tmp_path / "mine.txt"
    prog.write_text(PROGRAM)
    root = tmp_path / "runs"

    def make(**over):
        return ns.compose("export", {"runs_root": str(root), "program": str(prog), **over}, task="random-cross",
                          budget="tiny", baseline="prog")

    return make, root


def _a_run_directory(root):
    """A run directory under the runs root with a model in it, as training leaves one."""
    run = root / "random-cross" / "tiny" / "seed0" / "train" / "tf-full-k9"
    run.mkdir(parents=True)
    (run / "model.pt").write_bytes(b"weights of a week of training")
    return run


# --------------------------------------------------------------------------------- only an export is replaced
def test_overwrite_never_deletes_a_run_directory_or_a_users_folder(prog_cfg):
    make, root = prog_cfg
    run = _a_run_directory(root)
    mine = root / "my-notes"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    for target in (run, run.parent.parent, mine):
        with pytest.raises(ns.ConfigError, match="not an export folder.*not even overwrite=true"):
            ns.export(make(**{"export.dir": str(target), "overwrite": True}))
    assert (run / "model.pt").read_bytes() == b"weights of a week of training"
    assert (mine / "thesis.tex").read_text() == "precious"
    assert sorted(p.name for p in root.rglob("*") if p.name.startswith(".") and "tmp" in p.name) == []


def test_the_command_line_refuses_a_users_folder_in_one_line_even_with_overwrite(prog_cfg, tmp_path):
    make, root = prog_cfg
    mine = root / "results"
    mine.mkdir(parents=True)
    (mine / "table.csv").write_text("a,b\n")
    p = subprocess.run([*neurosym_cmd(), "export", "task=random-cross", "budget=tiny", "baseline=prog",
                        f"program={tmp_path / 'mine.txt'}", f"runs_root={root}", f"export.dir={mine}",
                        "overwrite=true"], capture_output=True, text=True, timeout=300)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode != 0 and len(lines) == 1 and "not an export folder" in lines[0], p.stderr
    assert (mine / "table.csv").read_text() == "a,b\n"


def test_an_export_holding_a_users_file_is_not_replaced_but_a_clean_one_is(prog_cfg):
    make, root = prog_cfg
    out = ns.export(make())
    folder = out["folder"]
    with pytest.raises(ns.ConfigError, match="exists; overwrite=true replaces it"):
        ns.export(make())
    notes = os.path.join(folder, "notes.txt")
    open(notes, "w").write("my calibration")
    with pytest.raises(ns.ConfigError, match="does not write: notes.txt"):
        ns.export(make(overwrite=True))
    assert open(notes).read() == "my calibration"
    os.remove(notes)
    again = ns.export(make(overwrite=True))  # an export, and nothing else: replaced
    assert again["folder"] == folder and json.load(open(os.path.join(folder, "manifest.json")))["program"]


def test_an_empty_folder_takes_an_export(prog_cfg):
    make, root = prog_cfg
    empty = root / "for-the-robot"
    empty.mkdir(parents=True)
    ns.export(make(**{"export.dir": str(empty)}))
    assert (empty / "manifest.json").is_file()


def test_of_two_exports_into_one_folder_the_second_to_finish_says_it_was_discarded(prog_cfg):
    """Both began when the folder was absent (or held the same old export); the first published; the second
    must not replace it silently."""
    from neurosym_cli.export.folder import claim
    from neurosym_cli.stages.export import export_dir, write_export

    make, root = prog_cfg
    cfg = make()
    folder = export_dir(cfg)
    seen_absent = claim(folder, overwrite=False)
    first = ns.export(cfg)  # finishes first
    with pytest.raises(ns.UserError, match="another export wrote .* this one is discarded"):
        write_export(cfg, folder, seen_absent)
    assert json.load(open(folder / "manifest.json"))["sha256"] == first_sha(first)
    cfg2 = make(overwrite=True)
    seen_old = claim(folder, overwrite=True)
    ns.export(cfg2)  # another overwrite finished meanwhile
    with pytest.raises(ns.UserError, match="another export wrote"):
        write_export(cfg2, folder, seen_old)
    assert not [p for p in folder.parent.iterdir() if ".tmp-" in p.name or ".old-" in p.name]


def first_sha(out):
    return json.load(open(os.path.join(out["folder"], "manifest.json")))["sha256"]


# --------------------------------------------------------------------------------- the check checks
def _check(folder):
    from neurosym_cli.export.check import run_check

    return run_check(folder)


def test_an_edited_program_json_fails_the_check(prog_cfg):
    make, root = prog_cfg
    folder = ns.export(make())["folder"]
    assert {r["file"]: r["status"] for r in _check(folder)["results"]}["program.json"] == "ok"
    path = os.path.join(folder, "program.json")
    spec = json.load(open(path))
    spec["rounds"][0][0]["score"][0][1] = 1.0  # the nearest becomes the farthest
    open(path, "w").write(json.dumps(spec))
    report = _check(folder)
    status = {r["file"]: r["status"] for r in report["results"]}
    assert status["program.json"] == "mismatch" and status["checksums"] == "mismatch", report["results"]
    assert report["first_mismatch"].startswith("program.json: episode"), report
    man = json.load(open(os.path.join(folder, "manifest.json")))  # without checksums, the replay alone fails it
    man.pop("sha256")
    open(os.path.join(folder, "manifest.json"), "w").write(json.dumps(man))
    assert _check(folder)["first_mismatch"].startswith("program.json: episode")
    with pytest.raises(ns.UserError, match="export check failed: program.json"):
        ns.export(make(), check=True)


def test_an_edit_no_golden_decision_notices_still_fails_the_check(prog_cfg):
    make, root = prog_cfg
    folder = ns.export(make())["folder"]
    with open(os.path.join(folder, "program.h"), "a") as f:
        f.write("/* tuned on the robot */\n")
    assert _check(folder)["first_mismatch"] == "program.h: changed after the export (its sha256 is not the " \
                                               "manifest's)"


def test_a_golden_file_without_episodes_fails_the_check(prog_cfg):
    make, root = prog_cfg
    folder = ns.export(make())["folder"]
    path = os.path.join(folder, "golden.json")
    meta = json.load(open(path))
    meta["episodes"] = []
    open(path, "w").write(json.dumps(meta))
    with pytest.raises(ns.UserError, match="golden.json lists no episode"):
        ns.export(make(), check=True)


def test_a_check_that_replays_nothing_fails(prog_cfg):
    make, root = prog_cfg
    folder = ns.export(make())["folder"]
    for name in ("program.py", "program.json", "program.h"):
        os.remove(os.path.join(folder, name))
    path = os.path.join(folder, "manifest.json")
    man = json.load(open(path))
    man.update(program=False, sha256={}, files=[f for f in man["files"] if not f.startswith("program.")])
    open(path, "w").write(json.dumps(man))
    report = _check(folder)
    assert report["exit"] == 1 and report["first_mismatch"].startswith("nothing was replayed"), report
    with pytest.raises(ns.UserError, match="export check failed: nothing was replayed"):
        ns.export(make(), check=True)


@pytest.mark.parametrize("tol", ["inf", "nan", "-1"])
def test_a_tolerance_that_accepts_anything_is_refused(prog_cfg, tol):
    make, root = prog_cfg
    with pytest.raises(ns.ConfigError, match="export.tolerance must be"):
        make(**{"export.tolerance": tol})
    folder = ns.export(make())["folder"]
    from neurosym_cli.export.check import run_check

    with pytest.raises(ns.UserError, match="tolerance must be a finite number >= 0"):
        run_check(folder, float(tol))
    p = subprocess.run([sys.executable, os.path.join(folder, "check.py"), "--tolerance", tol], capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 2 and "tolerance must be a finite number >= 0" in p.stderr, p.stdout + p.stderr


# --------------------------------------------------------------------------------- from a run to a robot
def test_export_then_check_with_the_default_relative_runs_root(tmp_path, monkeypatch):
    """The README's path: runs_root is `outputs`, relative to where the user stands."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.txt").write_text(PROGRAM)
    cfg = ns.compose("export", {"runs_root": "outputs", "program": "mine.txt"}, task="random-cross", budget="tiny",
                     baseline="prog")
    out = ns.export(cfg)
    assert not os.path.isabs(out["folder"])
    report = ns.export(cfg, check=True)
    assert report["first_mismatch"] is None and report["exit"] == 0
