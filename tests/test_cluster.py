"""From laptop to cluster: launcher presets and their errors, sweep ergonomics, run tracking, live views."""

import csv
import json
import logging
import subprocess
import sys

import pytest

from conftest import PAPER_METHOD, ROOT, run_dir
from test_cli import run


# --- launchers ------------------------------------------------------------------------------------------------

def test_missing_cluster_plugin_is_one_line_naming_the_extra(monkeypatch):
    from neurosym_cli.choices import check_launcher

    assert check_launcher(["-m", "hydra/launcher=slurm"]) is None  # installed here (dev extra)
    monkeypatch.setitem(sys.modules, "hydra_plugins.hydra_submitit_launcher", None)  # as if not installed
    for launcher in ("submitit_slurm", "submitit_local", "slurm", "slurm_local"):
        msg = check_launcher(["-m", "seed=0,1", f"hydra/launcher={launcher}"])
        assert msg == (f"hydra/launcher={launcher} needs the cluster extra: pip install -e '.[cluster]' in the "
                       "neurosym checkout (or pip install hydra-submitit-launcher)")
    assert check_launcher(["-m", "hydra/launcher=joblib"]) is None


def test_missing_plugin_through_the_console_script(tmp_path):
    code = ("import sys; sys.modules['hydra_plugins.hydra_submitit_launcher'] = None; "
            "from neurosym_cli.cli import main; "
            "sys.argv = ['neurosym', 'pipeline', '-m', 'seed=0,1', 'hydra/launcher=submitit_slurm']; main()")
    p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert p.returncode == 2
    assert p.stderr.strip() == ("neurosym pipeline: error: hydra/launcher=submitit_slurm needs the cluster extra: "
                                "pip install -e '.[cluster]' in the neurosym checkout (or pip install "
                                "hydra-submitit-launcher)")
    assert not (tmp_path / "outputs").exists()


def test_slurm_preset_composes_with_partition_and_time(tmp_path):
    p = run(["pipeline", "hydra/launcher=slurm", "hydra.launcher.partition=cpu", "hydra.launcher.timeout_min=30",
             "--cfg", "hydra", "-p", "hydra.launcher"], tmp_path)
    assert "SlurmLauncher" in p.stdout and "partition: cpu" in p.stdout and "timeout_min: 30" in p.stdout
    assert "max_num_timeout: 3" in p.stdout  # stages resume, so a timed-out job may be resubmitted


def test_exclusive_modes_and_resolved_cfg(tmp_path):
    p = run(["pipeline", "-m", "seed=0,1", "--cfg", "job"], tmp_path, check=False)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "cannot be combined" in p.stderr
    p = run(["synth", "task=random-grid", "--cfg", "job"], tmp_path)
    assert "rules: 2" in p.stdout and "${" not in p.stdout  # interpolations resolved: what the run would use


def test_swept_keys_and_job_prefix(monkeypatch):
    from neurosym_cli.cli import swept_keys
    from neurosym_cli.commands._run import job_prefix

    args = ["-m", "seed=0,1", "baselines=[tf-full,prog]", "lam=range(1,3)", "name='a,b'", "task=random-grid",
            "+rules=2,3", "x={a:1,b:2}"]
    assert swept_keys(args) == ["seed", "lam", "rules"]
    monkeypatch.setenv("NEUROSYM_SWEPT", "seed,lam")
    assert job_prefix(["seed=1", "budget=tiny", "lam=0.3"], 4) == "seed=1 lam=0.3"
    monkeypatch.setenv("NEUROSYM_SWEPT", "")
    assert job_prefix(["budget=tiny"], 4) == "job 4"


def test_submitit_local_two_seed_sweep_then_report(tmp_path):
    """The cluster path end to end on this machine: submitit's local executor runs one pipeline per seed as its own
    process (as SLURM would), then `neurosym report` aggregates the jobs' run directories. The paper's method
    (PAPER_METHOD: the program's labels are its tag's, not the front pick's): the launcher is what is tested."""
    p = run(["pipeline", "-m", "seed=0,1", "budget=tiny", "task=random-grid", "threads=1",
             "baselines=[tf-full,prog,prog-retrained]", "hydra/launcher=slurm_local", *PAPER_METHOD], tmp_path,
            timeout=600)
    for s in (0, 1):
        exp = tmp_path / f"random-grid/tiny/seed{s}"
        for label in ("tf-full", "prog-k2-lam0.5-v1", "prog-retrained-k2-lam0.5-v1"):
            assert (exp / "eval" / label / "metrics.json").exists(), (s, label, p.stdout)
    logs = sorted((tmp_path / "multirun/pipeline").glob("*/.submitit/*/*_log.out"))
    assert len(logs) == 2
    text = "".join(f.read_text() for f in logs)
    for s in (0, 1):
        assert f"[seed={s}] pipeline done: 6 stages for random-grid (tiny budget, seed {s})" in text
    p = run(["report", "task=random-grid", "budget=tiny"], tmp_path)
    rep = json.loads((tmp_path / "random-grid/tiny/report.json").read_text())["tasks"]["random-grid"]
    assert rep["seeds"] == [0, 1]
    assert rep["baselines"]["prog-retrained"]["train_seeds"] == 2


# --- run tracking -----------------------------------------------------------------------------------------------

def _scalars(logdir):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    acc = EventAccumulator(str(logdir))
    acc.Reload()
    return {tag: [(e.step, e.value) for e in acc.Scalars(tag)] for tag in acc.Tags()["scalars"]}


def test_tensorboard_logs_every_training_and_search_step(tmp_path):
    pytest.importorskip("tensorboard")
    run(["train", "budget=tiny", "task=random-grid", "logger=tensorboard"], tmp_path)
    exp = tmp_path / "random-grid/tiny/seed0"
    tb = _scalars(exp / "tensorboard/train-oracle")
    with open(exp / "train/oracle/history.csv", newline="") as f:
        hist = list(csv.DictReader(f))
    assert [s for s, _ in tb["train/loss"]] == [1, 2]  # tiny budget: 8 rollouts, 4 per step
    assert [v for _, v in tb["train/loss"]] == pytest.approx([float(h["loss"]) for h in hist])
    # the paper's MCMC (PAPER_METHOD): the tiny budget's 30 proposals, one step each (the hybrid search's vary)
    run(["synth", "budget=tiny", "task=random-grid", "logger=tensorboard", *PAPER_METHOD], tmp_path)
    tb = _scalars(exp / "tensorboard/synth-k2-lam0.5-v1")
    best = [v for _, v in tb["search/best"]]
    assert len(best) == 30 and all(b <= a + 1e-6 for a, b in zip(best, best[1:]))  # best never gets worse
    with open(exp / "synth/k2-lam0.5-v1/trace.csv", newline="") as f:
        assert best[-1] == pytest.approx(float(list(csv.DictReader(f))[-1]["best"]))
    # starting over replaces the curve instead of adding a second one
    run(["train", "budget=tiny", "task=random-grid", "logger=tensorboard", "overwrite=true"], tmp_path)
    assert len(list((exp / "tensorboard/train-oracle").glob("events.out.tfevents.*"))) == 1
    assert [s for s, _ in _scalars(exp / "tensorboard/train-oracle")["train/loss"]] == [1, 2]


def test_csv_logger_writes_no_event_files(tmp_path):
    run(["train", "budget=tiny", "task=random-grid"], tmp_path)
    assert not (tmp_path / "random-grid/tiny/seed0/tensorboard").exists()
    assert (tmp_path / "random-grid/tiny/seed0/train/oracle/history.csv").exists()


def test_tensorboard_missing_is_one_line(monkeypatch, tmp_path):
    from neurosym_cli.config import UserError
    from neurosym_cli.utils.tracking import TrackedRun, open_tracker

    monkeypatch.setitem(sys.modules, "torch.utils.tensorboard", None)
    run = TrackedRun(key="t/b/seed0/train-oracle", tags={}, tensorboard=tmp_path / "tb", store=tmp_path)
    with pytest.raises(UserError, match=r"pip install -e '\.\[tensorboard\]'"):
        open_tracker("tensorboard", run)
    open_tracker("csv", run).log(1, {"x": 1.0})  # the plain tracker needs nothing


def test_bad_logger_value(tmp_path):
    p = run(["train", "budget=tiny", "logger=neptune"], tmp_path, check=False)
    assert p.returncode != 0 and "choose csv, tensorboard, mlflow or wandb, several joined by +" in p.stderr


def test_training_curves_from_histories(tmp_path):
    from neurosym_cli.stages.results import histories, write_curves

    for seed, losses in ((0, [9.0, 5.0, 4.0]), (1, [8.0, 6.0, 3.0])):
        for model in ("oracle", "dist-k2", "retrained-k2-lam0.5-v1"):
            d = tmp_path / f"seed{seed}/train/{model}"
            d.mkdir(parents=True)
            rows = "".join(f"{i + 1},{50 * (i + 1)},{v},1.0,0.01,0.5\n" for i, v in enumerate(losses))
            (d / "history.csv").write_text("step,rollouts,loss,grad_norm,lr,seconds\n" + rows)
    runs = histories(tmp_path)
    assert [(r[0], r[1], r[2], len(r[3])) for r in runs] == [
        ("tf-full (the oracle)", "tf-full", False, 2), ("dist-k2", "dist", False, 2),
        ("prog-retrained k2-lam0.5-v1", "prog-retrained", True, 2)]
    assert runs[0][3][1] == [(50.0, 8.0), (100.0, 6.0), (150.0, 3.0)]
    png = write_curves(tmp_path, "test", tmp_path / "curves.png")
    assert png is not None and png.stat().st_size > 1000
    assert write_curves(tmp_path / "nothing", "test", tmp_path / "none.png") is None


def test_one_colour_per_baseline():
    from neurosym_cli.schemes import SCHEMES as BASELINES
    from neurosym_cli.plotting import baseline_of, color

    assert len({color(b) for b in BASELINES}) == len(BASELINES)
    assert baseline_of("prog-retrained-k2-lam0.5-v1") == "prog-retrained"
    assert baseline_of("det-prog-k5-lam0.5-v1") == "det-prog"
    assert baseline_of("hard-attn-k2") == "hard-attn" and baseline_of("tf-full") == "tf-full"


# --- live views -------------------------------------------------------------------------------------------------

class _Result:
    def __init__(self):
        from collections import Counter

        from neurosym_cli.synth.objective import Score

        self.best_score = Score(3.0, 2.0, 2.0)
        self.proposed, self.accepted = Counter(threshold=4, rule=2), Counter(threshold=1)
        self.seconds, self.proposals_per_second = 2.0, 3.0

    def acceptance(self):
        return {m: self.accepted[m] / n for m, n in sorted(self.proposed.items())}


def test_search_view_labels_progress_and_summary(caplog):
    from rich.console import Console

    from neurosym_cli.dsl.sampling import MOVE_HELP, MOVES
    from neurosym_cli.utils import console as cons

    assert set(MOVE_HELP) == set(MOVES)  # every move the search makes is explained
    res = _Result()
    with caplog.at_level(logging.INFO, logger="neurosym"):
        with cons.SearchDisplay("synth t", 10, 0.5, rich=False, moves=MOVE_HELP) as d:
            for step in range(1, 11):
                d.update(step, res, {"phase": "final"})
    lines = [r.getMessage() for r in caplog.records]
    # the first step is the warm-up, which measures no pace (utils/console.Eta): the time left is known from the second
    assert lines[0].startswith("synth t step 1/10 (0:00 elapsed, ? left)  best objective 3.0000 = L1 2.0000")
    assert lines[1].startswith("synth t step 2/10 (0:00 elapsed, 0:00 left)  best objective 3.0000 = L1 2.0000")
    assert "accepted per move: rule=0% threshold=25%" in lines[-1]
    view = cons.SearchDisplay("synth t", 10, 0.5, rich=True, moves=MOVE_HELP)
    rec = Console(record=True, width=300)
    monkey_console, cons.console = cons.console, rec
    try:
        with view:
            view.update(10, res, {"phase": "final"})
        rec.print(view._view(10, res, {"phase": "final"}))
    finally:
        cons.console = monkey_console
    text = rec.export_text()
    for label in ("10/10 steps (final)", "elapsed", "left", "objective", "= L1 action error", "+ 0.5 x max in+out",
                  "max in+out: the program's max_i (in_i + out_i) on the synthesis dataset D", "proposals/s", "moves: threshold = nudge one filter threshold"):
        assert label in text, label


def test_tiny_training_summary_says_what_it_averaged(tmp_path):
    p = run(["train", "budget=tiny", "task=random-grid"], tmp_path)
    assert "training loss" in p.stdout and "(mean of the last 2 of 2 steps)" in p.stdout
    m = json.loads((tmp_path / "random-grid/tiny/seed0/train/oracle/manifest.json").read_text())
    assert m["final_loss_steps"] == 2
    assert "elapsed" in p.stdout and "left)" in p.stdout


def test_readme_documents_the_cluster_extra():
    readme = (ROOT / "README.md").read_text()
    assert 'pip install -e ".[cluster]"' in readme and "hydra/launcher=slurm" in readme
    assert "logger=tensorboard" in readme


# --- sweep ergonomics -------------------------------------------------------------------------------------------

def test_a_sweep_job_with_a_missing_upstream_fails_alone(tmp_path):
    run(["train", "budget=tiny", "task=random-grid"], tmp_path)  # seed 0's oracle only
    p = run(["synth", "-m", "seed=0,1", "budget=tiny", "task=random-grid"], tmp_path, check=False)
    assert p.returncode == 1  # a failed job fails the command ...
    tag = run_dir("synth", tmp_path, "budget=tiny", "task=random-grid").program_tag  # the default search's
    assert (tmp_path / f"random-grid/tiny/seed0/synth/{tag}/program.txt").exists()  # ... not the others
    out = p.stdout + p.stderr
    assert "Traceback" not in out
    assert "[seed=1] neurosym synth: error: no checkpoint" in out and "neurosym train task=random-grid" in out
    assert "sweep of synth: 2 jobs" in out and "1 of 2 jobs failed" in out
    results = sorted((tmp_path / "multirun/synth").glob("*/*/job_result.json"))
    outcome = {json.loads(f.read_text())["job"]: json.loads(f.read_text()) for f in results}
    assert outcome[0]["ok"] and set(outcome[0]["row"]) == {"objective", "l1", "max in+out on D", "artifact"}
    assert outcome[0]["row"]["artifact"].endswith(f"random-grid/tiny/seed0/synth/{tag}/program.txt")
    assert not outcome[1]["ok"] and "no checkpoint" in outcome[1]["error"]


def test_sweep_comparison_table_of_a_successful_sweep(tmp_path):
    run(["train", "budget=tiny", "task=random-grid"], tmp_path)
    p = run(["synth", "-m", "lam=0.3,0.7", "budget=tiny", "task=random-grid"], tmp_path)
    assert "sweep of synth: 2 jobs" in p.stdout and "failed" not in p.stdout
    for lam in ("lam=0.3", "lam=0.7"):
        assert lam in p.stdout
    assert "artifact" in p.stdout and "program.txt" in p.stdout  # the table points to each job's program
    # a job whose config is invalid fails alone too (rules must stay below the team size)
    p = run(["synth", "-m", "rules=2,99", "budget=tiny", "task=random-grid"], tmp_path, check=False)
    assert p.returncode == 1 and "rules=99" in p.stdout and "1 of 2 jobs failed" in p.stdout


# --- Pareto front of a report ------------------------------------------------------------------------------------

def test_pareto_front_and_dominated_area_of_a_hand_made_set():
    from neurosym_cli.utils.pareto import dominated_area, pareto_front

    pts = [(1, 5), (2, 3), (3, 4), (4, 1), (2, 3), (5, 5), (4, 2)]
    assert pareto_front(pts) == [0, 1, 4, 3]  # (3, 4), (5, 5) and (4, 2) are dominated; equal points both stay
    # union of [x, 6] x [y, 6] over the front: 1 x 1 + 2 x 3 + 2 x 5
    assert dominated_area([pts[i] for i in pareto_front(pts)], (6, 6)) == pytest.approx(17.0)
    assert dominated_area(pts, (6, 6)) == pytest.approx(17.0)  # dominated points add nothing
    assert dominated_area([(7, 1)], (6, 6)) == 0.0  # beyond the reference
    assert pareto_front([(0, 0)]) == [0]
