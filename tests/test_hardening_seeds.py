"""Issue 38, seed statistics: a nan or inf in one seed's evaluation is refused in one line naming the file and the
key, never averaged into "nan ± nan", a place on the Pareto front or a dominated area of 0 or inf."""

import json

import pytest

from neurosym_cli import seeds
from neurosym_cli.stages import results
from neurosym_cli.utils.io import ArtifactError
from test_cli import run
from test_stats import three_seeds

BAD = (float("nan"), float("inf"), float("-inf"))


def _spoil(f, value, baseline="prog-retrained", metric="cost"):
    """Put ``value`` into one evaluation seed's ``metric`` of a seed file (json writes NaN / Infinity, and reads
    them back)."""
    r = json.loads(f.read_text())
    r["baselines"][baseline]["per_seed"][1][metric] = value
    f.write_text(json.dumps(r))


@pytest.mark.parametrize("value", BAD)
def test_a_non_finite_value_in_a_seed_file_is_refused_naming_file_and_key(tmp_path, value):
    three_seeds(tmp_path)
    f = tmp_path / "random-grid-seed1.json"
    _spoil(f, value, metric="max_degree")
    with pytest.raises(ArtifactError) as e:
        seeds.from_seed_files(sorted(tmp_path.glob("*.json")))
    msg = str(e.value)
    assert "\n" not in msg and str(f) in msg and "prog-retrained" in msg
    assert f"max_degree of evaluation seed 1 is {value}" in msg and "not a result" in msg


def test_report_over_seed_files_with_a_nan_exits_non_zero_and_writes_nothing(tmp_path):
    files = tmp_path / "seeds"
    files.mkdir()
    three_seeds(files)
    f = files / "random-grid-seed1.json"
    _spoil(f, float("nan"))
    p = run(["report", f"report.seed_files={files}", "report.reps=200"], tmp_path, check=False)
    err = p.stderr.strip().splitlines()
    assert p.returncode != 0 and len(err) == 1, p.stderr
    assert str(f) in err[0] and "cost of evaluation seed 1 is nan" in err[0], err
    assert "nan ± nan" not in p.stdout and not (files / "report").exists()


def _metrics(d, seed, value=1.0, label="tf-full"):
    """A metrics.json as `neurosym eval` writes it (the fields the readers use), one evaluation seed's loss
    ``value``."""
    d.mkdir(parents=True)
    rows = [{"seed": s, "episodes": 1, "cost": 2.0 + seed + s, **{m: 1.0 for m in seeds.METRICS if m != "cost"}}
            for s in range(2)]
    rows[1]["cost"] = value if value != 1.0 else rows[1]["cost"]
    summary = {m: {"mean": sum(r[m] for r in rows) / 2, "std": 0.0} for m in seeds.METRICS}
    cfg = {"seed": seed, "task": {"name": "random-grid"}, "budget": {"name": "tiny"}, "exp_dir": str(d.parents[1])}
    (d / "metrics.json").write_text(json.dumps({"baseline": label, "label": label, "per_seed": rows,
                                                "summary": summary, "config": cfg}))
    return d / "metrics.json"


def test_report_over_run_directories_with_an_inf_names_the_file_and_exits_non_zero(tmp_path):
    root = tmp_path / "random-grid" / "tiny"
    for s in range(2):
        _metrics(root / f"seed{s}" / "eval" / "tf-full", s)
        _metrics(root / f"seed{s}" / "eval" / "no-comm", s, label="no-comm")
    bad = _metrics(root / "seed2" / "eval" / "tf-full", 2, value=float("inf"))
    _metrics(root / "seed2" / "eval" / "no-comm", 2, label="no-comm")
    p = run(["report", f"report_dir={root}", "report.reps=200"], tmp_path, check=False)
    err = p.stderr.strip().splitlines()
    assert p.returncode != 0 and len(err) == 1, p.stderr
    assert str(bad) in err[0] and "cost of evaluation seed 1 is inf" in err[0] and "neurosym eval" in err[0], err
    assert not (root / "pareto.csv").exists() and not (root / "report.json").exists()


def test_one_run_directorys_table_refuses_a_nan_summary(tmp_path):
    """The table of one run directory (`neurosym eval`, the pipeline's closing table, its Pareto front) reads the
    summary means: a nan there is named by its key."""
    exp = tmp_path / "seed0"
    _metrics(exp / "eval" / "tf-full", 0)
    f = _metrics(exp / "eval" / "no-comm", 0, label="no-comm")
    m = json.loads(f.read_text())
    m["summary"]["max_degree"]["mean"] = float("nan")
    f.write_text(json.dumps(m))
    with pytest.raises(ArtifactError) as e:
        results.collect(exp, "neurosym pipeline task=random-grid")
    msg = str(e.value)
    assert "\n" not in msg and str(f) in msg and "summary.max_degree.mean is nan" in msg
    assert "neurosym pipeline task=random-grid" in msg
    m["summary"]["max_degree"]["mean"] = 1.0
    m["per_seed"][0]["max_in"] = float("-inf")
    f.write_text(json.dumps(m))
    with pytest.raises(ArtifactError, match="max_in of evaluation seed 0 is -inf"):
        results.collect(exp)
    m["per_seed"][0]["max_in"] = 1.0
    f.write_text(json.dumps(m))
    assert [label for label, _ in results.collect(exp)] == ["tf-full", "no-comm"]  # finite again: read as before
