"""A task's own metrics (Task.metrics) are columns of the results tables, not only fields of metrics.json (issue 40):
the table of one run directory (`neurosym eval`, the pipeline's) and the report across training seeds."""

import json

from neurosym_cli import seeds
from neurosym_cli.stages import results
from neurosym_cli.utils.console import console

import neurosym as ns


def _metrics(d, seed, label="tf-full", extra=None):
    """A metrics.json as `neurosym eval` writes it, with the task's own metrics ``extra`` (name -> value)."""
    d.mkdir(parents=True)
    extra = extra if extra is not None else {"spread": 0.25 + seed, "gap_share": 0.5}
    rows = [{"seed": s, "episodes": 1, **{m: 1.0 + s for m in seeds.SHARED}, **extra} for s in range(2)]
    summary = {m: {"mean": sum(r[m] for r in rows) / 2, "std": 0.0, "ci95": 0.0, "n": 2}
               for m in rows[0] if m not in ("seed", "episodes")}
    cfg = {"seed": seed, "task": {"name": "random-grid"}, "budget": {"name": "tiny"}, "exp_dir": str(d.parents[1])}
    (d / "metrics.json").write_text(json.dumps({"baseline": label, "label": label, "per_seed": rows,
                                                "summary": summary, "config": cfg}))


def _text(renderable) -> str:
    with console.capture() as cap:
        console.print(renderable, width=250)
    return cap.get()


def test_the_run_directorys_table_shows_the_tasks_own_metrics(tmp_path):
    cfg = ns.compose("eval", {"runs_root": str(tmp_path), "plots": False}, task="random-grid", budget="tiny")
    _metrics(tmp_path / "random-grid" / "tiny" / "seed0" / "eval" / "tf-full", 0)
    _metrics(tmp_path / "random-grid" / "tiny" / "seed0" / "eval" / "no-comm", 0, "no-comm", extra={})
    with console.capture() as cap:
        results.print_table(cfg)
    head, *lines = [line for line in cap.get().splitlines() if "tf-full" in line or "spread" in line]
    assert "spread" in head and "gap_share" in head and "collisions" in head
    assert "0.250 ± 0.000" in lines[0] and "0.500 ± 0.000" in lines[0]  # tf-full's own metrics
    assert [c for c, _ in results.columns(["cost", "spread", "max_in"])][-1] == "spread"  # after the shared ones


def test_the_report_across_seeds_shows_them_too(tmp_path):
    root = tmp_path / "random-grid" / "tiny"
    for s in range(2):
        _metrics(root / f"seed{s}" / "eval" / "tf-full", s)
    summary = seeds.summarize(seeds.from_runs_root(root), reps=50)
    assert summary.rows["tf-full"]["spread"]["mean"] == 0.75  # seeds 0 and 1: 0.25 and 1.25
    text = _text(results.across_table(summary))
    row = next(line for line in text.splitlines() if "tf-full" in line)
    assert "spread" in text and "gap_share" in text and "0.750 ± " in row
    assert any(r["metric"] == "spread" for r in seeds.csv_rows(summary))
