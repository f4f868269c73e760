"""A runs root's folders and the files of report, eval's plot, render and figures are named once, in run/layout.py:
the reader finds what the writer's names make, and the names on disk stay the ones docs and benchmarks read."""

import re
from pathlib import Path

from neurosym_cli.run import layout
from neurosym_cli.run.layout import METRICS_FILE, RunFolder, RunsRoot, fail_suffix, seed_dir

ROOT = Path(__file__).resolve().parents[1]


def _evaluate(root: Path, task_dir: str, budget: str, seed: int, label: str) -> Path:
    m = root / task_dir / budget / seed_dir(seed) / layout.EVAL / label / METRICS_FILE
    m.parent.mkdir(parents=True)
    m.write_text("{}")
    return m


def test_a_runs_root_finds_its_evaluations_and_reads_task_and_failure_back(tmp_path):
    a = _evaluate(tmp_path, "random-grid" + fail_suffix(0.5), "tiny", 0, "tf-full")
    b = _evaluate(tmp_path, "two-groups-cross" + fail_suffix(0), "tiny", 1, "no-comm")
    c = _evaluate(tmp_path, "two-groups-cross", "tiny", 0, "dist")
    (tmp_path / "two-groups-cross" / "quick" / "notes" / layout.EVAL / "x").mkdir(parents=True)  # not a seed dir
    root = RunsRoot(tmp_path)
    assert root.evaluations() == sorted([a, b, c])
    assert root.runs_evaluated() == [("random-grid-fail0.5", "tiny"), ("two-groups-cross", "tiny")]
    assert [RunsRoot.parse_task_dir(t) for t, _ in root.runs_evaluated()] == [("random-grid", "0.5"),
                                                                            ("two-groups-cross", None)]
    assert RunsRoot.parse_task_dir("a-fail-task-fail1e-05") == ("a-fail-task", "1e-05")
    assert RunsRoot.parse_seed_dir(seed_dir(12)) == 12 and RunsRoot.parse_seed_dir("seedx") is None
    assert RunsRoot(tmp_path / "nothing").evaluations() == []


def test_the_names_on_disk_are_the_ones_docs_and_benchmarks_read(tmp_path):
    run = RunFolder(tmp_path)
    assert (run.figure2_file.name, run.curves_file.name) == ("figure2.png", "curves.png")
    assert (layout.REPORT_JSON, layout.REPORT_CSV, layout.IMPROVEMENT_CSV) == ("report.json", "report.csv",
                                                                              "improvement.csv")
    assert layout.seeds_plane_file("random-cross") == "seeds-random-cross.png"
    stem = layout.episode_stem(0)
    assert run.rendered("tf-full", stem) == tmp_path / "render" / "tf-full" / "episode0.gif"
    assert layout.episode_stem(3, [0, 1.5, -2, 3]) == "episode3-window0_1.5_-2_3"
    assert layout.frames_file(stem) == "episode0-frames.png"
    assert run.figure_file(layout.RULES, "k2-lam0.5-v1", episode=0).name == "rules-k2-lam0.5-v1-episode0.png"
    assert layout.figure_name(layout.RULES, "t", episode=1, round_=2) == "rules-t-episode1-round2.png"
    assert layout.figure_name(layout.TRAJECTORIES, "t") == "trajectories-t.png"
    (run.render_root / "dist").mkdir(parents=True)
    (run.render_root / "dist" / "episode0.gif").write_bytes(b"")
    assert run.renders(stem) == [run.rendered("dist", stem)]


def test_no_reader_or_writer_spells_these_names_itself():
    """The literals of a runs root's glob, the task folder's pattern and report/plot/render names live in layout."""
    patterns = [r'"\*/\*/seed\*', r"-fail\(\[", r'"(figure2|curves|pareto|report|report_curves)\.png"',
                r'"(pareto|improvement|report)\.csv"', r'"report(_marl_eval)?\.json"', r"seeds-\{", r'"episode0\.gif',
                r'f"(attention|trajectories|figure1|figure5|rules)-\{', r'\{stem\}-frames\.png']
    files = [p for p in (ROOT / "neurosym_cli").rglob("*.py") if p.name != "layout.py"
             and "standalone" not in p.parts and p.name != "check.py"]  # export's check report is another file
    files += [ROOT / "benchmarks" / "main_job.py", ROOT / "benchmarks" / "results" / "collect.py"]
    bad = [f"{p.relative_to(ROOT)}:{k + 1}" for p in files for k, line in enumerate(p.read_text().splitlines())
           if not line.lstrip().startswith("#") and any(re.search(pat, line) for pat in patterns)]
    assert not bad, bad
