"""A task of one's own, from outside the package: the ring example (examples/ring) through every verb and the joblib
launcher, a user's YAML in a config directory of their own, the Python API, and the one-line refusals."""

import json
import os
import subprocess
import textwrap

import pytest

from conftest import ROOT, neurosym_cmd, run_dir

RING = ROOT / "examples" / "ring" / "conf"


def run(args, cwd, check=True, timeout=300):
    env = {**os.environ, "NEUROSYM_RUNS": str(cwd)}
    p = subprocess.run([*neurosym_cmd(), *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    if check and p.returncode != 0:
        raise AssertionError(f"exit {p.returncode}\nstdout:\n{p.stdout}\nstderr:\n{p.stderr}")
    return p


def one_line(p) -> str:
    assert p.returncode != 0 and "Traceback" not in p.stderr, p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, p.stderr
    return lines[0]


@pytest.mark.slow
def test_the_ring_example_runs_every_verb_from_outside_the_package(tmp_path):
    """train, synth, retrain, eval, show-program, render and a two-job joblib sweep on the example task, run from
    a directory that is not the repository, with the ring's own observation widths (Ds = Dp = 4)."""
    cd = ["--config-dir", str(RING)]
    common = ["task=ring", "budget=tiny", "plots=false", "threads=1"]
    run(["train", *cd, *common, "task.radius=3.5"], tmp_path)
    ckpt = tmp_path / "ring/tiny/seed0/train/oracle/model.pt"
    import torch

    payload = torch.load(ckpt, weights_only=True)
    assert payload["arch"]["obs_dim"] == 4 and payload["arch"]["pair_dim"] == 4
    assert payload["config"]["task"]["radius"] == 3.5 and payload["config"]["task"]["_target_"] == "ring.RingTask"
    run(["synth", *cd, *common, "task.radius=3.5"], tmp_path)
    ring = run_dir("synth", tmp_path, *common, "task.radius=3.5", config_dir=RING)  # the task's objective, search's
    assert ring.program_tag.startswith("k2-lam0.5-v1-scaled")
    program = (ring.synth_dir / "program.txt").read_text()
    from neurosym_cli.dsl import parse

    assert len(parse(program).rounds[0]) >= 1
    run(["retrain", *cd, *common, "task.radius=3.5"], tmp_path)
    p = run(["eval", *cd, *common, "task.radius=3.5", "baseline=prog-retrained"], tmp_path)
    retrained = run_dir("eval", tmp_path, *common, "task.radius=3.5", "baseline=prog-retrained", config_dir=RING)
    m = json.loads((retrained.eval_dir() / "metrics.json").read_text())
    assert set(m["summary"]) >= {"cost", "max_in", "collisions"} and m["summary"]["cost"]["mean"] > 0
    # a resumed model under another task config is refused, naming the key
    p = run(["train", *cd, *common, "task.radius=5.0", "budget.train_rollouts=16"], tmp_path, check=False)
    assert "task.radius=3.5" in one_line(p)
    p = run(["show-program", *cd, "task=ring", "budget=tiny"], tmp_path)
    assert "its" in p.stdout or "my" in p.stdout
    p = run(["render", *cd, *common, "task.radius=3.5", "episode=0", "render.every=4"], tmp_path)
    assert list((tmp_path / "ring/tiny/seed0/render").rglob("*.gif"))
    # a joblib sweep: the workers import the user's module by themselves (nothing is registered at run time)
    p = run(["synth", "-m", *cd, *common, "task.radius=3.5", "rules=1,2", "hydra/launcher=joblib",
             "hydra.launcher.n_jobs=2"], tmp_path)
    assert (run_dir("synth", tmp_path, *common, "task.radius=3.5", "rules=1", config_dir=RING).synth_dir
            / "program.txt").exists()


@pytest.mark.slow
def test_select_with_a_tiny_grid_on_the_example(tmp_path):
    """`neurosym select`'s process pool imports the ring task too."""
    cd = ["--config-dir", str(RING)]
    common = ["task=ring", "budget=tiny", "plots=false", "threads=1"]
    run(["train", *cd, *common], tmp_path)
    run(["select", *cd, *common, "select.lam=[0.5]", "select.rules=[1,2]", "select.features=[v1]", "select.jobs=2",
         "select.finalists=1"], tmp_path)
    sel = json.loads((tmp_path / "ring/tiny/seed0/select/selected.json").read_text())
    assert sel["task"] == "ring" and sel["rules"] in (1, 2)


def test_a_yaml_of_ones_own_with_a_new_schema_field(tmp_path):
    """A user's own YAML and module in their own directory: the checker knows the schema's keys and suggests the
    closest; a task module that does not import is one line with the import error."""
    conf = tmp_path / "myconf" / "task"
    conf.mkdir(parents=True)
    (tmp_path / "mytask.py").write_text(textwrap.dedent('''
        from dataclasses import dataclass
        import sys
        sys.path.insert(0, %r)
        from ring import RingTask, RingConfig

        @dataclass
        class BigRingConfig(RingConfig):
            _target_: str = "mytask.BigRing"
            obstacles: int = 3
            """a field no other task has"""

        class BigRing(RingTask):
            Config = BigRingConfig
    ''' % str(ROOT / "examples" / "ring")))
    (conf / "big-ring.yaml").write_text("_target_: mytask.BigRing\nname: big-ring\nradius: 5.0\n")
    (conf / "broken.yaml").write_text("_target_: nosuchmodule.Task\nname: broken\n")
    (conf / "lazy.yaml").write_text("_target_: mytask.BigRingConfig\nname: lazy\n")
    cd = ["--config-dir", str(tmp_path / "myconf")]
    p = run(["train", *cd, "task=big-ring", "budget=tiny", "task.obstacles=5", "--cfg", "job"], tmp_path)
    assert "obstacles: 5" in p.stdout
    assert "did you mean 'task.obstacles'" in one_line(run(["train", *cd, "task=big-ring", "task.obstacle=5"],
                                                            tmp_path, check=False))
    line = one_line(run(["train", *cd, "task=broken", "budget=tiny"], tmp_path, check=False))
    assert "cannot import 'nosuchmodule'" in line and "ModuleNotFoundError" in line
    line = one_line(run(["train", *cd, "task=lazy", "budget=tiny"], tmp_path, check=False))
    assert "lacks" in line and "reset()" in line
    line = one_line(run(["train", *cd, "task=big-rnig"], tmp_path, check=False))
    assert "big-ring" in line  # the user's tasks are among the choices
    p = run(["--help"], tmp_path)
    assert "random-cross" in p.stdout


def test_a_missing_capability_is_one_line(tmp_path):
    """stress needs with_team_size; unlabeled-goals' programs read one feature per goal, so it has none."""
    run(["train", "task=unlabeled-goals", "budget=tiny", "plots=false"], tmp_path)
    line = one_line(run(["stress", "task=unlabeled-goals", "budget=tiny", "plots=false"], tmp_path, check=False))
    assert "with_team_size" in line and "stress" in line


def test_the_python_api_trains_searches_and_evaluates(tmp_path):
    """The API composes the CLI's config, is quiet, returns objects, and the CLI reads what it wrote."""
    import torch

    import neurosym as ns

    cfg = ns.compose(task="ring", budget="tiny", runs_root=str(tmp_path), config_dir=str(RING), threads=1)
    assert cfg.task.radius == 3.0 and cfg.exp_dir == f"{tmp_path}/ring/tiny/seed0"
    out = ns.train(cfg)
    assert out["checkpoint"].endswith("model.pt")
    program = ns.synth(cfg)
    assert isinstance(program, ns.Program) and ns.parse(ns.to_text(program)) == program
    metrics = ns.evaluate(cfg, "prog")
    assert metrics["cost"]["n"] == cfg.budget.eval_seeds and metrics["cost"]["mean"] > 0
    saved = torch.load(tmp_path / "ring/tiny/seed0/train/oracle/model.pt", weights_only=True)
    assert saved["config"]["task"]["radius"] == 3.0 and saved["config"]["budget"]["name"] == "tiny"
    task = ns.task(cfg)
    state = task.reset(1, torch.Generator().manual_seed(0))[0]
    obs = task.observe(state, ns.Rng(torch.Generator().manual_seed(1)))
    picks = ns.picks(program, cfg, obs.agent[0], obs.rel[0])
    assert picks.shape == (8, len(program.rounds[0])) and int(picks.max()) < 8
    assert (picks != torch.arange(8)[:, None]).all()  # nobody hears itself
    p = run(["eval", "--config-dir", str(RING), "task=ring", "budget=tiny", "baseline=prog", "plots=false"], tmp_path)
    assert p.returncode == 0  # the command line takes what Python made
    with pytest.raises(ns.UserError, match="did you mean"):
        ns.compose(task="ring", config_dir=str(RING), overrides={"task.radus": 1.0})


def test_an_installed_package_offers_a_task_by_entry_point(tmp_path):
    """A distribution's entry point in the group neurosym.tasks is a task= choice, with no config directory."""
    site = tmp_path / "site"
    dist = site / "ringpkg-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: ringpkg\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[neurosym.tasks]\nring-ep = ring:RingTask\n")
    env = {**os.environ, "NEUROSYM_RUNS": str(tmp_path),
           "PYTHONPATH": os.pathsep.join([str(site), str(ROOT / "examples" / "ring"), os.environ.get("PYTHONPATH", "")])}
    p = subprocess.run([*neurosym_cmd(), "train", "task=ring-ep", "budget=tiny", "plots=false", "task.radius=2.5"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    import torch

    saved = torch.load(tmp_path / "ring-ep/tiny/seed0/train/oracle/model.pt", weights_only=True)
    assert saved["config"]["task"]["_target_"] == "ring:RingTask" and saved["config"]["task"]["radius"] == 2.5
