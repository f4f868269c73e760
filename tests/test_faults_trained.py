"""Faults and hostile input, faults on a trained run directory (issue 28, item 4): hand-written programs, NaN, full
disks, read-only seed directories, memory, checkpoints of other shapes, corrupt JSON, quoted paths: every bad
input is one line and a non-zero exit, and no result is lost silently. docs/reliability.md lists the promises and
what tests each; the other classes of fault are the other tests/test_faults_*.py files (shared helpers:
tests/fault_helpers.py)."""

import os
import subprocess
from pathlib import Path
from typing import Callable

import pytest

from conftest import run_dir
from fault_helpers import EXP, TINY, one_line_error, run
from neurosym_cli.utils.io import ArtifactError


# ------------------------------------------------------------------------------------------ issue 28, item 4
@pytest.fixture(scope="module")
def trained_root(tmp_path_factory):
    """A runs root with random-grid's tiny oracle and its synthesized program (made once for this module)."""
    root = tmp_path_factory.mktemp("trained")
    run(["train", "task=random-grid", "budget=tiny", "threads=1"], root)
    run(["synth", "task=random-grid", "budget=tiny", "threads=1"], root)
    return root


@pytest.fixture
def runs(trained_root, tmp_path):
    """A private copy of ``trained_root`` (a test may break its artifacts)."""
    import shutil

    shutil.copytree(trained_root, tmp_path / "runs", symlinks=True)
    return tmp_path / "runs"


def test_a_hand_written_programs_metrics_record_its_own_k(runs):
    """Issue 28, item 2: K of a program given as program=FILE is the file's (3 rules), not the config's rules=2."""
    import json

    prog = runs / "three.txt"
    prog.write_text("random(filter(d <= 2.0, l))\nrandom(filter(d <= 3.0, l))\nrandom(filter(gy >= -1.0, l))\n")
    run(["eval", "baseline=prog", *TINY, f"program={prog}"], runs)
    (out,) = (runs / EXP / "eval").glob("prog-file-three-*/metrics.json")
    assert json.loads(out.read_text())["rules"] == 3
    run(["eval", "baseline=prog", *TINY], runs)  # the synthesized program's is its search's K
    label = run_dir("eval", runs, "baseline=prog", *TINY).label  # prog- and the default search's tag
    assert json.loads((runs / EXP / f"eval/{label}/metrics.json").read_text())["rules"] == 2


def test_no_nan_from_a_finite_model_or_a_nan_dataset(runs):
    """Issue 28, item 1: a dataset D holding a nan is never searched on (collected again), an oracle whose
    rollouts overflow (weights finite, 1e30 times too large) is refused by synth and eval in one line, and no
    metrics.json or program is written from it."""
    import torch

    data = runs / EXP / "synth/dataset-r4-s10.pt"
    payload = torch.load(data, weights_only=True)
    payload["buckets"][0]["rel"].view(-1)[0] = float("nan")
    torch.save(payload, data)
    p = run(["synth", *TINY, "overwrite=true"], runs)
    assert "holds non-finite values (buckets[0].rel); collecting it again" in p.stdout + p.stderr
    assert all(torch.isfinite(b["rel"]).all() for b in torch.load(data, weights_only=True)["buckets"])
    ckpt = runs / EXP / "train/oracle/model.pt"
    payload = torch.load(ckpt, weights_only=True)
    for w in payload["state_dict"].values():
        w.mul_(1e30)
    torch.save(payload, ckpt)
    data.unlink()
    one_line_error(run(["synth", *TINY, "overwrite=true"], runs, check=False), "rollouts reached non-finite values")
    assert not data.exists()
    one_line_error(run(["eval", "baseline=tf-full", *TINY], runs, check=False), "gave a non-finite cost")
    assert not (runs / EXP / "eval/tf-full").exists()


def _mount_tmpfs(where: Path, size: str) -> bool:
    """A small tmpfs at ``where`` (root only): a disk that really fills up."""
    where.mkdir(parents=True, exist_ok=True)
    return subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)],
                          capture_output=True).returncode == 0


def _fill(disk: Path, leave_kib: int) -> None:
    """Fill ``disk`` up to ``leave_kib`` KiB of free space."""
    st = os.statvfs(disk)
    free = st.f_bavail * st.f_frsize // 1024
    with open(disk / "filler", "ab") as f:
        f.write(b"\0" * max(0, free - leave_kib) * 1024)


def test_a_write_that_fails_leaves_the_old_file_and_no_temp_file(tmp_path, monkeypatch):
    """The artifact IO layer under a full disk (simulated: every write of a temp file fails with ENOSPC): one
    ArtifactError naming the file, the previous version intact, no temp file left; a pair written together
    (metrics.json and metrics.csv) changes both or neither."""
    import errno

    from neurosym_cli.utils import io

    (tmp_path / "a.json").write_text('{"old": 1}')
    (tmp_path / "a.csv").write_text("old\n")
    real = Path.write_bytes

    def full(self, data):
        if self.name.endswith(".tmp.csv"):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, data)

    monkeypatch.setattr(Path, "write_bytes", full)
    with pytest.raises(ArtifactError, match="no space left on the disk of .*a.csv"):
        io.write_together({tmp_path / "a.json": b'{"new": 1}', tmp_path / "a.csv": b"new\n"})
    assert (tmp_path / "a.json").read_text() == '{"old": 1}' and (tmp_path / "a.csv").read_text() == "old\n"
    with pytest.raises(ArtifactError, match="no space left"):
        io.write_csv(tmp_path / "a.csv", [{"x": 1}])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "a.json"]  # no temp file left


def test_a_disk_that_fills_up_is_one_line_and_nothing_half_written(runs, tmp_path):
    """Issue 28, item 4, on a real 4 MB tmpfs (root only): train and eval stop with one line; nothing that reads
    as complete is half-written; after space is freed the same command finishes."""
    import json

    import torch

    disk = tmp_path / "disk"
    if not _mount_tmpfs(disk, "4m"):
        pytest.skip("needs root to mount a tmpfs (test_a_write_that_fails_... simulates it)")
    try:
        import shutil

        shutil.copytree(runs / EXP / "synth", disk / EXP / "synth")  # no model yet: train must write one
        _fill(disk, 60)  # Hydra's logs fit, the 59 KB checkpoint and its history do not
        one_line_error(run(["train", *TINY], disk, check=False), "no space left on the disk")
        assert not list(disk.rglob("model.pt")) and not list(disk.rglob("*.tmp*"))
        (disk / "filler").unlink()
        run(["train", *TINY], disk)
        assert torch.load(disk / EXP / "train/oracle/model.pt", weights_only=True)["done"]
        for leave in (40, 20, 8):  # the disk fills at another write each time (logs, metrics, figures)
            _fill(disk, leave)
            p = run(["eval", "baseline=tf-full", *TINY], disk, check=False)
            assert "Traceback" not in p.stderr, p.stderr
            if p.returncode:
                assert "no space left on the disk" in p.stderr.strip().splitlines()[-1], p.stderr
            (disk / "filler").unlink()
            for m in disk.rglob("metrics.json"):  # whatever is there reads as a whole evaluation
                assert json.loads(m.read_text())["summary"]["cost"]["mean"] > 0
            assert not list(disk.rglob("*.tmp*"))
    finally:
        subprocess.run(["umount", "-l", str(disk)])


def _read_only(directory: Path) -> Callable[[], None] | None:
    """Make ``directory`` read-only (a read-only bind mount for root, whom permissions do not stop; else the mode
    bits); returns what undoes it, or None when it cannot be done here."""
    if os.geteuid() == 0:
        ok = subprocess.run(["mount", "--bind", str(directory), str(directory)], capture_output=True).returncode == 0
        ok = ok and subprocess.run(["mount", "-o", "remount,ro,bind", str(directory)],
                                   capture_output=True).returncode == 0
        return (lambda: subprocess.run(["umount", "-l", str(directory)])) if ok else None
    modes = {p: p.stat().st_mode for p in [directory, *directory.rglob("*")] if p.is_dir()}
    for p in modes:
        p.chmod(0o555)
    return lambda: [p.chmod(m) for p, m in modes.items()]


def test_a_read_only_seed_directory(runs, tmp_path):
    """Issue 28, item 4: an archived (read-only) seed directory: train and eval stop with one line (whether
    Hydra's logs or our artifacts meet it first), show-program reads it (logging elsewhere), nothing changes."""
    seed = runs / EXP
    before = sorted((p.relative_to(seed), p.stat().st_size) for p in seed.rglob("*") if p.is_file())
    undo = _read_only(seed)
    if undo is None:
        pytest.skip("cannot make a directory read-only here")
    try:
        logs = f"hydra.run.dir={tmp_path / 'logs'}"
        for args in (["train", "overwrite=true"], ["train", "budget.train_rollouts=12"], ["eval", "baseline=tf-full"],
                     ["eval", "baseline=tf-full", logs], ["train", "overwrite=true", logs]):
            one_line_error(run([*args, *TINY], runs, check=False), "read-only")
        assert "random(filter(" in run(["show-program", *TINY, logs], runs).stdout
    finally:
        undo()
    assert sorted((p.relative_to(seed), p.stat().st_size) for p in seed.rglob("*") if p.is_file()) == before


def test_a_team_too_large_for_memory_is_one_line(tmp_path):
    """Issue 28, item 4: a team too large for memory (here under a 4 GB address-space limit) is one line: the
    estimate's refusal before allocating (policy/footprint.py; issue 26) where the machine's free memory is below
    what the team needs, else the allocator's error naming the size asked for and what to make smaller."""
    import resource

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))

    p = run(["train", *TINY, "task.agents_per_group=1500"], tmp_path, check=False, preexec_fn=limit)
    last = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ""
    one_line_error(p, "does not fit" if "does not fit" in last else "out of memory (it asked for")
    assert "the largest team that fits is N =" in last or "a smaller team" in last, p.stderr
    from neurosym_cli.errors import resource_problem

    assert resource_problem(MemoryError()).startswith("out of memory")
    assert resource_problem(ValueError("x")) is None  # a bug keeps its traceback


_MUTATIONS = {
    "a weight missing": lambda p: p["state_dict"].pop(next(iter(p["state_dict"]))),
    "a weight of another shape": lambda p: p["state_dict"].update({next(iter(p["state_dict"])): _zeros(3, 3)}),
    "no architecture": lambda p: p.pop("arch"),
    "an architecture of another type": lambda p: p["arch"].update(obs_dim="x"),
    "an unknown architecture key": lambda p: p["arch"].update(hidden=-5),
    "weights not a dict": lambda p: p.update(state_dict=[1]),
    "no resume state": lambda p: p.pop("fit"),
    "no done flag": lambda p: p.pop("done"),
}


def _zeros(*shape):
    import torch

    return torch.zeros(*shape)


@pytest.mark.parametrize("what", list(_MUTATIONS))
def test_a_checkpoint_with_missing_keys_or_other_shapes_is_refused(trained_root, tmp_path, what):
    """Issue 28, item 4: a checkpoint of the right format tag whose keys are missing or whose weights have other
    shapes is one line at load time (never half-loaded)."""
    import torch

    from neurosym_cli.run.checkpoints import load_checkpoint

    payload = torch.load(trained_root / EXP / "train/oracle/model.pt", weights_only=True)
    _MUTATIONS[what](payload)
    torch.save(payload, tmp_path / "model.pt")
    with pytest.raises(ArtifactError, match="is not a usable checkpoint.*re-run `neurosym train"):
        load_checkpoint(tmp_path / "model.pt", "neurosym train")


def test_a_checkpoint_of_other_shapes_through_the_commands(runs):
    """The same through eval, synth and a resume; and a resume state (Adam's moments) of other shapes."""
    import torch

    ckpt = runs / EXP / "train/oracle/model.pt"
    good = torch.load(ckpt, weights_only=True)
    payload = torch.load(ckpt, weights_only=True)
    _MUTATIONS["a weight of another shape"](payload)
    torch.save(payload, ckpt)
    for verb in (["eval", "baseline=tf-full"], ["synth", "overwrite=true"], ["train", "budget.train_rollouts=12"]):
        one_line_error(run([*verb, *TINY], runs, check=False), "is not a usable checkpoint")
    good["fit"]["optimizer"]["state"][0]["exp_avg"] = torch.zeros(2)
    torch.save(good, ckpt)
    one_line_error(run(["train", *TINY, "budget.train_rollouts=12"], runs, check=False),
                   "its resume state does not fit this model")


@pytest.mark.parametrize("content", ["[1, 2]", '{"rules": "x", "lam": [], "synth": 3}', "not json", '{"a": "b"}'])
def test_corrupt_json_artifacts_name_the_command_that_writes_them_again(runs, content):
    """Issue 28, item 4: metrics.json, selected.json, pipeline_timings.json and summary.json corrupt or of another
    shape or type: one line that names the command writing them again."""
    import dataclasses

    import neurosym_cli.api as ns
    from neurosym_cli.stages.synth import read_summary

    exp = runs / EXP
    (exp / "select").mkdir()
    (exp / "select/selected.json").write_text(content)
    one_line_error(run(["eval", "baseline=prog", "selected=true", *TINY], runs, check=False),
                   "delete it and run `neurosym select task=random-grid budget=tiny seed=0`")
    (exp / "pipeline_timings.json").write_text(content)
    one_line_error(run(["pipeline", "baselines=[tf-full]", *TINY], runs, check=False),
                   "delete it and run `neurosym pipeline task=random-grid budget=tiny seed=0`")
    (exp / "eval/tf-full").mkdir(parents=True)
    (exp / "eval/tf-full/metrics.json").write_text(content)  # read by the table every eval prints
    one_line_error(run(["eval", "baseline=prog", *TINY], runs, check=False),
                   "delete it and run `neurosym pipeline task=random-grid budget=tiny seed=0`")
    tag = run_dir("synth", runs, *TINY).program_tag  # the default search's
    (exp / f"synth/{tag}/summary.json").write_text(content)  # select reads every round's time
    cfg = dataclasses.replace(ns.compose("synth", task="random-grid", budget="tiny"), runs_root=str(runs),
                              exp_dir=str(exp))
    with pytest.raises(ArtifactError, match=r"delete it and run `neurosym synth .* overwrite=true`"):
        read_summary(cfg)


def test_suggested_commands_quote_paths_with_spaces(runs):
    """Issue 28, item 4: a printed command with a path holding spaces runs as printed (shlex quoting)."""
    import shlex

    folder = runs / "my programs"
    folder.mkdir()
    (folder / "two rules.txt").write_text("random(filter(d <= 2.5, l))\nrandom(filter(d <= 3.0, l))\n")
    p = run(["eval", "baseline=prog-retrained", *TINY, f"program={folder / 'two rules.txt'}"], runs, check=False)
    line = p.stderr.strip().splitlines()[-1]
    printed = line.split("create it with `", 1)[1].rstrip("`")
    assert shlex.quote(f"program={folder / 'two rules.txt'}") in printed
    words = shlex.split(printed)
    assert words[:2] == ["neurosym", "retrain"]
    run([*words[1:], "threads=1"], runs)
    run(["eval", "baseline=prog-retrained", *TINY, f"program={folder / 'two rules.txt'}"], runs)
