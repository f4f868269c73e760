"""The CLI as a user runs it, in subprocesses, on the tiny budget."""

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import ROOT, front_pick, neurosym_cmd, picked_labels, run_dir


def run(args, tmp_path, check=True, timeout=300, plots=False):
    """The console script in a subprocess; the PNGs of eval, pipeline and report are off (plots=false) unless a
    test checks them: matplotlib was a third of a tiny eval's time."""
    env = {**os.environ, "NEUROSYM_RUNS": str(tmp_path)}
    if args and not args[0].startswith("-") and not any(a.startswith("plots=") for a in args):
        args = [*args, f"plots={str(plots).lower()}"]
    p = subprocess.run([*neurosym_cmd(), *args], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=timeout)
    if check and p.returncode != 0:
        raise AssertionError(f"exit {p.returncode}\nstdout:\n{p.stdout}\nstderr:\n{p.stderr}")
    return p


def test_help_lists_commands_without_importing_torch():
    code = ("import sys; sys.argv=['neurosym','--help']; from neurosym_cli.cli import main; main(); "
            "assert 'torch' not in sys.modules, 'torch imported'")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    for cmd in ("train", "eval", "synth", "retrain", "show-program"):
        assert cmd in p.stdout


def test_train_then_eval_tiny(tmp_path):
    run(["train", "task=random-cross", "budget=tiny"], tmp_path)
    exp = tmp_path / "random-cross" / "tiny" / "seed0"
    assert (exp / "train" / "oracle" / "model.pt").exists()
    assert len((exp / "train" / "oracle" / "history.csv").read_text().splitlines()) == 3  # header + 2 steps
    for baseline in ("tf-full", "hard-attn"):
        p = run(["eval", "task=random-cross", f"baseline={baseline}", "budget=tiny"], tmp_path)
        assert "tf-full" in p.stdout
    m = json.loads((exp / "eval" / "hard-attn-k5" / "metrics.json").read_text())
    assert m["seeds"] == 2 and m["episodes_per_seed"] == 6
    assert m["summary"]["max_in"]["mean"] == pytest.approx(5.0)
    rows = (exp / "eval" / "hard-attn-k5" / "metrics.csv").read_text().splitlines()
    assert rows[0].startswith("seed,episodes,cost") and len(rows) == 3
    # eval is reproducible: same seeds, same numbers
    run(["eval", "task=random-cross", "baseline=hard-attn", "budget=tiny"], tmp_path)
    again = json.loads((exp / "eval" / "hard-attn-k5" / "metrics.json").read_text())
    assert again["per_seed"] == m["per_seed"]


def test_own_model_baselines_and_unlabeled(tmp_path):
    run(["train", "task=unlabeled-goals", "baseline=dist", "budget=tiny"], tmp_path)
    run(["eval", "task=unlabeled-goals", "baseline=dist", "budget=tiny"], tmp_path)
    m = json.loads((tmp_path / "unlabeled-goals/tiny/seed0/eval/dist-k5/metrics.json").read_text())
    assert m["summary"]["max_in"]["mean"] == pytest.approx(5.0)
    assert 0 <= m["summary"]["cost"]["mean"] <= 10


def test_resume_extend_and_already_done(tmp_path):
    run(["train", "task=two-groups-cross", "budget=tiny"], tmp_path)
    p = run(["train", "task=two-groups-cross", "budget=tiny"], tmp_path)
    assert "already trained" in p.stdout
    p = run(["train", "task=two-groups-cross", "budget=tiny", "budget.train_rollouts=16"], tmp_path)
    assert "resuming" in p.stdout and "step 2/4" in p.stdout
    hist = (tmp_path / "two-groups-cross/tiny/seed0/train/oracle/history.csv").read_text().splitlines()
    assert len(hist) == 5
    p = run(["train", "task=two-groups-cross", "budget=tiny", "model.width=8"], tmp_path, check=False)
    assert p.returncode != 0 and "trained with model.width=16, this run has 8" in p.stderr and "Traceback" not in p.stderr


def test_interrupted_train_resumes(tmp_path):
    env = {**os.environ, "NEUROSYM_RUNS": str(tmp_path)}
    args = [*neurosym_cmd(), "train", "task=two-groups-cross", "budget=tiny", "budget.train_rollouts=4000"]
    # a shell may start background jobs with SIGINT ignored, and Python keeps that; restore the default
    restore = lambda: signal.signal(signal.SIGINT, signal.SIG_DFL)  # noqa: E731
    proc = subprocess.Popen(args, cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=restore)
    ckpt = tmp_path / "two-groups-cross/tiny/seed0/train/oracle/model.pt"
    deadline = time.time() + 120
    while not ckpt.exists() and time.time() < deadline:
        time.sleep(0.2)
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode != 0 and "re-run the same command to resume" in err, err
    # the same command again picks up from the checkpoint (stopped as soon as it says so)
    proc = subprocess.Popen(args, cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    header, first = proc.stdout.readline(), proc.stdout.readline()  # the run's header line, then its first
    proc.kill()
    proc.communicate()
    assert "neurosym train: task=two-groups-cross budget=tiny" in header, header
    assert "resuming" in first and "from step" in first, first


def test_multirun_two_seeds(tmp_path):
    run(["train", "-m", "seed=0,1", "budget=tiny", "task=two-groups-cross"], tmp_path)
    for s in (0, 1):
        assert (tmp_path / f"two-groups-cross/tiny/seed{s}/train/oracle/model.pt").exists()
    a = json.loads((tmp_path / "two-groups-cross/tiny/seed0/train/oracle/manifest.json").read_text())
    b = json.loads((tmp_path / "two-groups-cross/tiny/seed1/train/oracle/manifest.json").read_text())
    assert a["final_loss"] != b["final_loss"]


def test_joblib_launcher_sweep(tmp_path):
    p = run(["train", "-m", "seed=0,1", "budget=tiny", "task=two-groups-cross", "hydra/launcher=joblib",
             "hydra.launcher.n_jobs=2"], tmp_path)
    for s in (0, 1):
        assert (tmp_path / f"two-groups-cross/tiny/seed{s}/train/oracle/model.pt").exists()
    out = p.stdout + p.stderr
    assert "Joblib.Parallel(" not in out and "joblib: launching 2 jobs, n_jobs=2 at a time" in out
    # each job's lines name the swept value, so parallel jobs' lines can be told apart
    for s in (0, 1):
        assert f"[seed={s}] done train two-groups-cross oracle seed{s}" in out
        assert f"[seed={s}] train two-groups-cross oracle seed{s} step 1/2" in out


def test_same_seed_same_model(tmp_path):
    import torch

    run(["train", "budget=tiny", "task=two-groups-cross", "runs_root=" + str(tmp_path / "a")], tmp_path)
    run(["train", "budget=tiny", "task=two-groups-cross", "runs_root=" + str(tmp_path / "b")], tmp_path)
    load = lambda r: torch.load(tmp_path / r / "two-groups-cross/tiny/seed0/train/oracle/model.pt", weights_only=True)
    a, b = load("a"), load("b")
    assert all(torch.equal(a["state_dict"][k], b["state_dict"][k]) for k in a["state_dict"])


@pytest.mark.parametrize("args,needle", [
    (["train", "task=nope", "budget=tiny"], "nope"),
    (["train", "baseline=nope", "budget=tiny"], "nope"),
    (["train", "budget=tiny", "budget.train_rollouts=-3"], "train_rollouts must be positive"),
    (["train", "budget=tiny", "budget.train_rollouts=abc"], "train_rollouts"),
    (["eval", "budget=tiny", "baseline=dist"], "neurosym train task=random-cross baseline=dist"),
    (["frobnicate"], "unknown command"),
    (["synth", "budget=tiny", "synth.backend=fortran"], "synth.backend must be auto, numba or torch"),
])
def test_bad_input_is_one_clear_error(tmp_path, args, needle):
    p = run(args, tmp_path, check=False)
    assert p.returncode != 0
    assert needle in p.stderr
    assert "Traceback" not in p.stderr + p.stdout


def test_a_mistyped_command_names_the_nearest_and_every_command(tmp_path):
    import neurosym as ns
    from neurosym_cli.commands import COMMANDS

    p = run(["pipline", "task=random-grid"], tmp_path, check=False)
    err = p.stderr.strip().splitlines()
    assert p.returncode == 2 and len(err) == 1 and not p.stdout, p.stderr
    assert err[0].startswith("neurosym: error: unknown command 'pipline'; did you mean 'pipeline'? choose one of: ")
    assert err[0].endswith(", ".join(COMMANDS))
    with pytest.raises(ns.UserError, match="unknown command 'trian'; did you mean 'train'"):
        ns.compose("trian")


def test_corrupt_checkpoint_is_reported(tmp_path):
    ckpt = tmp_path / "random-cross/tiny/seed0/train/oracle/model.pt"
    ckpt.parent.mkdir(parents=True)
    ckpt.write_bytes(b"not a checkpoint")
    p = run(["eval", "budget=tiny"], tmp_path, check=False)
    assert p.returncode != 0 and "corrupt checkpoint" in p.stderr and "Traceback" not in p.stderr


def _rule_rows(stdout: str) -> list[list[str]]:
    """The rows of show-program's rule table (#, rule, features read, reading, ...), each cell's wrapped lines joined
    by a space: a long reading wraps within its column, beside the row's other cells."""
    rows: list[list[str]] = []
    for line in stdout.splitlines():
        parts = line.split("│")  # the panel's border, the table's, its cells, the table's, the panel's
        if not line.startswith("│ │") or len(parts) < 7:
            continue
        cells = [c.strip() for c in parts[2:-2]]
        if cells[0].isdigit() or not rows:
            rows.append(cells)
        else:
            rows[-1] = [f"{a} {b}".strip() for a, b in zip(rows[-1], cells)]
    return rows


def test_synth_show_program_eval_smoke(tmp_path):
    run(["train", "task=random-grid", "budget=tiny"], tmp_path)
    run(["synth", "task=random-grid", "budget=tiny"], tmp_path)
    tag = run_dir("synth", tmp_path, "task=random-grid", "budget=tiny").program_tag  # the default search's
    out = tmp_path / "random-grid/tiny/seed0/synth" / tag
    text = (out / "program.txt").read_text()
    from neurosym_cli.dsl import parse

    prog = parse(text)
    assert prog.n_rounds == 1 and len(prog.rounds[0]) == 2
    summary = json.loads((out / "summary.json").read_text())
    assert summary["rounds"][0]["proposals_per_second"] > 0
    assert abs(summary["rounds"][0]["full_forward_check"] - summary["rounds"][0]["objective"]) < 1e-3
    assert (out / "trace.csv").read_text().splitlines()[0].startswith("round,step,phase,move,accepted")
    p = run(["show-program", "task=random-grid", "budget=tiny"], tmp_path)
    from fixtures import feature_map
    from neurosym_cli.dsl import describe, rule_text

    flat = " ".join(p.stdout.replace("│", " ").split())  # rich pads and wraps cells; compare the words
    vocab = feature_map("formation").vocab
    rows = _rule_rows(p.stdout)
    assert len(rows) == len(prog.rounds[0]), p.stdout
    for rule, row in zip(prog.rounds[0], rows):  # every rule, in the paper's notation and read out, in its row
        assert row[1] == rule_text(rule) and describe(rule, vocab) in row[3], (row, p.stdout)
    assert f"objective {summary['rounds'][0]['objective']:.4f}" in flat
    p = run(["eval", "task=random-grid", "baseline=prog", "budget=tiny"], tmp_path)
    m = json.loads((tmp_path / f"random-grid/tiny/seed0/eval/prog-{tag}/metrics.json").read_text())
    assert m["summary"]["max_in"]["mean"] <= 2.0
    # det-prog: argmax rules only
    run(["synth", "task=random-grid", "budget=tiny", "baseline=det-prog"], tmp_path)
    det = parse((tmp_path / f"random-grid/tiny/seed0/synth/det-{tag}/program.txt").read_text())
    assert det.deterministic
    # an existing program is reused; overwrite=true searches again: same seed, same program, byte for byte
    p = run(["synth", "task=random-grid", "budget=tiny"], tmp_path)
    assert "already synthesized" in p.stdout
    (out / "program.txt").write_text("# stale\n" + text)
    run(["synth", "task=random-grid", "budget=tiny", "overwrite=true"], tmp_path)
    assert (out / "program.txt").read_text() == text
    # the torch back-end of the scorer runs the same search: the same program and objective, byte for byte
    run(["synth", "task=random-grid", "budget=tiny", "overwrite=true", "synth.backend=torch"], tmp_path)
    assert (out / "program.txt").read_text() == text
    assert json.loads((out / "summary.json").read_text())["rounds"][0]["backend"] == "torch"


def test_synth_two_rounds_and_sweep(tmp_path):
    run(["train", "task=unlabeled-goals", "budget=tiny"], tmp_path)
    run(["synth", "-m", "task=unlabeled-goals", "budget=tiny", "rules=1,2", "lam=0.3,0.7"], tmp_path)
    from neurosym_cli.dsl import parse

    base = tmp_path / "unlabeled-goals/tiny/seed0/synth"
    for k in (1, 2):
        for lam in (0.3, 0.7):
            tag = run_dir("synth", tmp_path, "task=unlabeled-goals", "budget=tiny", f"rules={k}", f"lam={lam}")
            p = parse((base / tag.program_tag / "program.txt").read_text())
            assert p.n_rounds == 2 and all(len(r) == k for r in p.rounds)
    assert len(list(base.glob("dataset-*.pt"))) == 1  # collected once, reused by the sweep


def test_show_program_needs_no_torch_and_reports_bad_text(tmp_path):
    prog = tmp_path / "p.txt"
    prog.write_text("argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nrandom(filter(d >= 3.41, l)\n")
    code = ("import sys; sys.argv=['neurosym','show-program','program=" + str(prog) + "'];"
            "from neurosym_cli.cli import main\ntry:\n main()\nexcept SystemExit: pass\n"
            "assert 'torch' not in sys.modules, 'torch imported'")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert "p.txt:2:28: expected ')'" in p.stderr, p.stderr
    assert "Traceback" not in p.stderr
    prog.write_text("argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nrandom(filter(d >= 3.41, l))\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert "ask the nearest agent" in p.stdout and "torch imported" not in p.stderr, p.stderr  # the task's words
    p = run(["show-program", f"program={prog}"], tmp_path)
    assert "ask the nearest agent whose bearing (rad) is at least -1.85" in p.stdout


def _no_torch(args, tmp_path):
    """The console's main on ``args`` in a subprocess (runs root tmp_path) that fails when torch was imported."""
    code = (f"import sys; sys.argv=['neurosym', *{list(args)!r}];"
            "from neurosym_cli.cli import main\ntry:\n main()\nexcept SystemExit as e:\n code = e.code\n"
            "else:\n code = 0\nassert 'torch' not in sys.modules, 'torch imported'\nsys.exit(code)")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path,
                          env={**os.environ, "NEUROSYM_RUNS": str(tmp_path)}, timeout=120)


def test_report_needs_no_torch(tmp_path):
    from test_hardening_seeds import _metrics

    root = tmp_path / "random-grid" / "tiny"
    for s in range(2):
        _metrics(root / f"seed{s}" / "eval" / "tf-full", s)
        _metrics(root / f"seed{s}" / "eval" / "no-comm", s, label="no-comm")
    p = _no_torch(["report", "task=random-grid", "budget=tiny", "report.reps=200", "plots=false"], tmp_path)
    assert p.returncode == 0 and "torch imported" not in p.stderr, p.stderr
    assert "tf-full" in p.stdout and (root / "report.json").is_file()


def test_show_program_of_a_run_with_a_front_needs_no_torch(tmp_path):
    tag = run_dir("show_program", tmp_path, "task=random-grid", "budget=tiny").program_tag  # what show-program reads
    synth = tmp_path / "random-grid" / "tiny" / "seed0" / "synth" / tag
    synth.mkdir(parents=True)
    silent, near = "random(filter(false, l))", "argmax(map(-1.0*d, filter(true, l)))"
    (synth / "program.txt").write_text(f"{near}\n{near}\n")
    rows = [{"budget": b, "l1": l1, "l1_ratio": l1 / 2.0, "degree": b, "max_in": b / 2, "max_out": b / 2,
             "program": p} for b, l1, p in ((0.0, 2.0, silent), (2.0, 0.5, near))]
    (synth / "front.json").write_text(json.dumps({"rounds": [{"round": r, "budgets": rows} for r in (1, 2)]}))
    p = _no_torch(["show-program", "task=random-grid", "budget=tiny"], tmp_path)
    assert p.returncode == 0 and "torch imported" not in p.stderr, p.stderr
    assert "degree-budget front" in p.stdout and "Traceback" not in p.stderr


def test_synth_before_train_names_the_command(tmp_path):
    p = run(["synth", "task=random-grid", "budget=tiny"], tmp_path, check=False)
    assert p.returncode != 0
    assert "neurosym train task=random-grid baseline=tf-full budget=tiny seed=0" in p.stderr
    p = run(["eval", "task=random-grid", "baseline=prog", "budget=tiny"], tmp_path, check=False)
    assert p.returncode != 0 and "neurosym" in p.stderr and "Traceback" not in p.stderr


def test_retrain_smoke(tmp_path):
    run(["train", "task=random-grid", "budget=tiny"], tmp_path)
    p = run(["retrain", "task=random-grid", "budget=tiny"], tmp_path, check=False)
    assert p.returncode != 0 and "neurosym synth task=random-grid" in p.stderr  # needs the program first
    run(["synth", "task=random-grid", "budget=tiny"], tmp_path)
    run(["retrain", "task=random-grid", "budget=tiny"], tmp_path)
    tag = run_dir("retrain", tmp_path, "task=random-grid", "budget=tiny").program_tag  # the default search's
    assert (tmp_path / f"random-grid/tiny/seed0/train/retrained-{tag}/model.pt").exists()
    run(["eval", "task=random-grid", "budget=tiny", "baseline=prog-retrained"], tmp_path)
    m = json.loads((tmp_path / f"random-grid/tiny/seed0/eval/prog-retrained-{tag}/metrics.json").read_text())
    assert m["summary"]["max_in"]["mean"] <= 2.0
    # the same rules under new comments: still the same program, nothing to do
    prog = tmp_path / f"random-grid/tiny/seed0/synth/{tag}/program.txt"
    prog.write_text("# edited by hand\n" + prog.read_text())
    assert "already trained" in run(["retrain", "task=random-grid", "budget=tiny"], tmp_path).stdout
    # another program under the same name (its summary records the searched one): neither retrained nor evaluated
    # under it; a program and its summary are one unit (run/summary.py)
    prog.write_text("random(filter(true, l))\nrandom(filter(true, l))\n")
    for verb in (["retrain"], ["eval", "baseline=prog-retrained"]):
        p = run([*verb, "task=random-grid", "budget=tiny"], tmp_path, check=False)
        assert p.returncode == 1 and len(p.stderr.strip().splitlines()) == 1 and "overwrite=true" in p.stderr
        assert "is not the program its summary.json records" in p.stderr


def test_pipeline_tiny_reuses_artifacts(tmp_path):
    base = "baselines=[tf-full,dist,prog,prog-retrained,dt,dt-retrained]"
    p = run(["pipeline", "task=random-grid", "budget=tiny", base], tmp_path, plots=True)
    assert "pipeline done" in p.stdout
    # long work says how long it has left: every stage of the pipeline as a whole, and each part of its figures
    lines = [ln for ln in p.stdout.splitlines() if "pipeline stage " in ln]
    n = int(lines[0].split("pipeline stage 1/")[1].split(":")[0])
    assert len(lines) == n and all(re.search(r"\(\d+:\d\d elapsed, (\d+:\d\d|\?) left", ln) for ln in lines)
    figures = [ln for ln in p.stdout.splitlines() if "figures random-grid " in ln]
    assert figures and all(" left" in ln for ln in figures)
    exp = tmp_path / "random-grid/tiny/seed0"
    # prog and prog-retrained run under the program the front selection picked (pipeline.select=front)
    picked = picked_labels(tmp_path, "task=random-grid", "budget=tiny")
    for label in ("tf-full", "dist-k2", picked["prog"], picked["prog-retrained"], "dt-k2-v1", "dt-retrained-k2-v1"):
        assert (exp / "eval" / label / "metrics.json").exists(), label
    assert (exp / "eval/figure2.png").stat().st_size > 1000
    timings = json.loads((exp / "pipeline_timings.json").read_text())
    pick = Path(front_pick(tmp_path, "task=random-grid", "budget=tiny")["program_file"])
    assert {"train tf-full", "synth prog", f"retrain prog-retrained {pick.stem}", "eval dt"} <= set(timings)
    p = run(["pipeline", "task=random-grid", "budget=tiny", base], tmp_path)
    # every training (train and retrain) and every search of the plan finds its artifact and does nothing
    from neurosym_cli.stages.graph import plan

    stages = plan(base.split("=")[1].strip("[]").split(","))
    trainings = [s for s in stages if s.verb in ("train", "retrain")]  # tf-full, dist, prog- and dt-retrained
    assert len(trainings) == 4
    # ... and so does the front selection's: the oracle, no-comm, a retraining per candidate, prog's search
    search = run_dir("synth", tmp_path, "task=random-grid", "budget=tiny")
    candidates = json.loads(search.front_choice_file(search.program_tag).read_text())["candidates"]
    assert p.stdout.count("already trained") == len(trainings) + 1 + len(candidates)  # + no-comm, which it needs
    assert p.stdout.count("already synthesized") == len([s for s in stages if s.verb == "synth"]) == 2
    # a rerun reuses the artifacts and keeps the time each took to make
    assert json.loads((exp / "pipeline_timings.json").read_text())["train tf-full"] == timings["train tf-full"]


def test_per_seed_pipelines_and_report(tmp_path):
    run(["pipeline", "-m", "seed=0,1", "task=random-grid", "budget=tiny", "baselines=[tf-full,prog]"], tmp_path)
    assert not list(tmp_path.glob("random-grid/tiny/seed*/eval/*.png"))  # plots=false: tables and files only
    p = run(["report", "task=random-grid", "budget=tiny", "report.reps=1000"], tmp_path, plots=True)
    words = " ".join(p.stdout.replace("│", " ").split())
    assert "random-grid: 2 training seeds (0, 1)" in words
    assert "mean ± 95 % Student-t interval across training seeds (1 degree of freedom)" in words
    p = run(["report", f"report_dir={tmp_path / 'random-grid/tiny/seed1'}"], tmp_path, plots=True)
    words = " ".join(p.stdout.replace("│", " ").split())  # rich wraps a title that holds a long path
    assert "random-grid: 1 training seed (1)" in words and "no interval across one training seed" in words
    assert (tmp_path / "random-grid/tiny/seed1/report.png").exists()
    rep = json.loads((tmp_path / "random-grid/tiny/report.json").read_text())["tasks"]["random-grid"]
    assert set(rep["baselines"]) == {"tf-full", "prog"} and rep["seeds"] == [0, 1]
    assert rep["baselines"]["prog"]["labels"] == [  # each seed's prog runs under its own front's pick
        picked_labels(tmp_path, "task=random-grid", "budget=tiny", f"seed={s}")["prog"] for s in (0, 1)]
    assert rep["baselines"]["tf-full"]["train_seeds"] == 2 and rep["baselines"]["tf-full"]["cost"]["ci95"] > 0
    for png in ("report.png", "report_curves.png", "pareto.png", "seeds-random-grid.png"):
        assert (tmp_path / "random-grid/tiny" / png).stat().st_size > 1000, png
    assert not (tmp_path / "random-grid/tiny/seeds-profile.png").exists()  # no no-comm: nothing to normalize by
    pareto = (tmp_path / "random-grid/tiny/pareto.csv").read_text().splitlines()
    assert pareto[0].startswith("label,max_degree,loss,non_dominated") and len(pareto) == 3
    assert (tmp_path / "random-grid/tiny/report.csv").read_text().startswith(
        "task,baseline,labels,metric,train_seeds,seeds,mean,ci95_half")
    marl = json.loads((tmp_path / "random-grid/tiny/report_marl_eval.json").read_text())
    assert set(marl["neurosym"]["random-grid"]["prog"]) == {"seed0", "seed1"}
    p = run(["report", "task=random-cross", "budget=tiny"], tmp_path, check=False)
    assert p.returncode != 0 and "neurosym pipeline task=random-cross" in p.stderr
