"""The result files of benchmarks/ (docs/results/*.json, run_seeds' seed files) go through the one atomic JSON
writer (utils/io.write_json): a temp file of their own, and the committed format byte for byte."""

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(params=["files", "run_seeds"])
def write(request):
    if request.param == "files":
        from benchmarks.results.files import write
    else:
        from benchmarks.run_seeds import write_result as write
    return write


def test_a_committed_result_file_is_written_again_byte_for_byte(tmp_path, write):
    for name in ("docs/results/random-cross.json", "docs/results/seeds/random-cross-seed0.json"):
        committed = (ROOT / name).read_bytes()
        write(tmp_path / "again.json", json.loads(committed))
        assert (tmp_path / "again.json").read_bytes() == committed


def test_another_writers_temp_file_is_left_alone(tmp_path, write):
    """Two writers of results side by side (seed files of one task, collect's variants) never share a temp name:
    a file named like a fixed '<name>.tmp' is not taken or replaced."""
    theirs = tmp_path / "random-cross-seed0.tmp"
    theirs.write_text("another writer's half-written file\n")
    write(tmp_path / "random-cross-seed0.json", {"b": 1, "a": [1, 2]})
    assert theirs.read_text() == "another writer's half-written file\n"
    assert (tmp_path / "random-cross-seed0.json").read_text() == '{\n "a": [\n  1,\n  2\n ],\n "b": 1\n}\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["random-cross-seed0.json", "random-cross-seed0.tmp"]
