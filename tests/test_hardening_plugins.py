"""Issue 38, plugins and the Python path: a user's files beside them never replace a module of Python's, their task
modules still load the documented way, and a task of their own that misbehaves is one line naming it."""

import shutil
import subprocess
import sys

import pytest

from conftest import ROOT
from test_plugins import RING, one_line, run

SHADOWS = {"datetime.py": "raise RuntimeError('the user datetime.py was imported')\n",
           "queue.py": "raise RuntimeError('the user queue.py was imported')\n"}


def _shadowing_cwd(tmp_path):
    """A working directory holding datetime.py and queue.py that fail when imported, the ring task's module (found
    there, the documented way) and its YAML in a config directory elsewhere (whose parent does not hold it)."""
    for name, text in SHADOWS.items():
        (tmp_path / name).write_text(text)
    shutil.copy(ROOT / "examples" / "ring" / "ring.py", tmp_path / "ring.py")
    conf = tmp_path / "elsewhere" / "conf"
    shutil.copytree(RING, conf)
    return conf


def test_a_users_datetime_and_queue_in_the_working_directory_are_not_imported(tmp_path):
    """The console script and its joblib workers (started with `python -m`, which puts the working directory first)
    import Python's datetime and queue; the user's task module in the working directory still loads, in both."""
    conf = _shadowing_cwd(tmp_path)
    p = run(["train", "-m", "--config-dir", str(conf), "task=ring", "budget=tiny", "plots=false", "threads=1",
             "seed=0,1", "hydra/launcher=joblib", "hydra.launcher.n_jobs=2"], tmp_path, check=False)
    assert p.returncode == 0 and "user" not in p.stderr, p.stderr[-3000:]
    assert all((tmp_path / f"ring/tiny/seed{s}/train/oracle/model.pt").exists() for s in (0, 1))


def test_python_dash_m_drops_the_working_directory_too(tmp_path):
    """`python -m neurosym_cli.cli` (the working directory first on sys.path) behaves as the console script."""
    conf = _shadowing_cwd(tmp_path)
    code = ("import sys, runpy; sys.argv = ['neurosym', 'train', '--config-dir', %r, 'task=ring', 'budget=tiny', "
            "'--cfg', 'job']; runpy.run_module('neurosym_cli.cli', run_name='__main__')" % str(conf))
    p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "_target_: ring.RingTask" in p.stdout, p.stderr[-3000:]
    # the datetime and queue that ran are Python's (a user's would have raised)
    probe = ("import sys; sys.argv = ['neurosym', '--version']; import runpy; "
             "runpy.run_module('neurosym_cli.cli', run_name='__main__'); import datetime, queue; "
             "print(datetime.__file__, queue.__file__)")
    p = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and str(tmp_path) not in p.stdout, p.stdout + p.stderr


def test_a_task_module_named_like_a_standard_module_says_so(tmp_path):
    """A task module of the user's named like one of Python's (queue.py) cannot win any more: the error says
    whose module was imported and to rename theirs."""
    conf = tmp_path / "conf" / "task"
    conf.mkdir(parents=True)
    (tmp_path / "queue.py").write_text("class MyTask:\n    pass\n")
    (conf / "mine.yaml").write_text("_target_: queue.MyTask\nname: mine\n")
    line = one_line(run(["train", "--config-dir", str(tmp_path / "conf"), "task=mine", "budget=tiny"], tmp_path,
                        check=False))
    assert "has no 'MyTask'" in line and "rename your module" in line and str(tmp_path / "queue.py") in line


# ------------------------------------------------------------------------------------- a task of one's own
BAD_TASKS = '''
import torch
from ring import RingTask


class NanCost(RingTask):
    """A cost that is nan everywhere."""
    def cost(self, next_state, action):
        return super().cost(next_state, action) * float("nan")


class NanWhenMoving(RingTask):
    """A cost that is finite at rest and nan once an agent moves: the probe passes, the first rollout does not."""
    def cost(self, next_state, action):
        c = super().cost(next_state, action)
        return torch.where(action.abs().sum((1, 2)) > 0, c * float("nan"), c)


class WrongShape(RingTask):
    """A feature of the asking agent computed as (B, N, N) instead of (B, N, 1)."""
    def features(self, version):
        fm = super().features(version)
        fns = dict(fm.fns)
        fns["sd"] = lambda v: v.agent[..., 0:1].expand(-1, -1, v.n_agents).contiguous()
        return type(fm)(fm.vocab, fns, fm.version)
'''


def _own_tasks(tmp_path, **targets):
    """ring.py and bad.py in the working directory, a config directory with one YAML per (name, target)."""
    shutil.copy(ROOT / "examples" / "ring" / "ring.py", tmp_path / "ring.py")
    (tmp_path / "bad.py").write_text(BAD_TASKS)
    conf = tmp_path / "conf" / "task"
    conf.mkdir(parents=True, exist_ok=True)
    for name, target in targets.items():
        (conf / f"{name}.yaml").write_text(f"_target_: {target}\nname: {name}\n")
    return ["--config-dir", str(tmp_path / "conf")]


def test_a_yaml_named_like_a_built_in_task_is_refused(tmp_path):
    cd = _own_tasks(tmp_path)
    (tmp_path / "conf" / "task" / "random-grid.yaml").write_text("_target_: ring.RingTask\nname: random-grid\n")
    line = one_line(run(["train", *cd, "task=random-grid", "budget=tiny", "--cfg", "job"], tmp_path, check=False))
    assert "random-grid.yaml has the name of a built-in task" in line and "task=my-random-grid" in line


@pytest.mark.parametrize("body", ["import sys\nsys.exit()\n", "raise SystemExit(0)\n", "import sys\nsys.exit(3)\n"])
def test_a_task_module_that_exits_at_import_is_one_line_and_non_zero(tmp_path, body):
    cd = _own_tasks(tmp_path, quitter="quitter.Task")
    (tmp_path / "quitter.py").write_text(body)
    line = one_line(run(["train", *cd, "task=quitter", "budget=tiny"], tmp_path, check=False))
    assert "cannot import 'quitter'" in line and "sys.exit(" in line and "while being imported" in line
    assert not (tmp_path / "quitter").exists()


def test_a_feature_of_the_wrong_shape_is_one_line_naming_it(tmp_path):
    cd = _own_tasks(tmp_path, shapes="bad.WrongShape")
    common = ["task=shapes", "budget=tiny", "plots=false", "threads=1"]
    run(["train", *cd, *common], tmp_path)  # the oracle reads observations, not features
    line = one_line(run(["synth", *cd, *common], tmp_path, check=False))
    assert "feature 'sd'" in line and "(B, N, 1)" in line and "the asking agent" in line


def test_feature_shapes_are_checked_where_they_are_built():
    """Also where they would broadcast silently: an (N, N) feature of the asking agent with B = N."""
    import torch

    from neurosym_cli.dsl.vocabulary import Feature
    from neurosym_cli.errors import ConfigError
    from neurosym_cli.tasks.features import custom_map

    mine = Feature("m", "self", "mine", "", (-9.0, 9.0))
    theirs = Feature("t", "other", "theirs", "", (-9.0, 9.0))
    b = n = 3
    agent, rel = torch.zeros(b, n, 2), torch.zeros(b, n, n, 2)
    for fm_m, fm_t, bad, what in [
        (lambda v: torch.zeros(b, n, n), lambda v: torch.zeros(b, n, n), "m", "shape (3, 3, 3)"),
        (lambda v: torch.zeros(b, n, 1), lambda v: torch.zeros(b, n), "t", "shape (3, 3)"),
        (lambda v: torch.zeros(b, n, 1), lambda v: torch.zeros(b, n, n, dtype=torch.long), "t", "torch.int64"),
        (lambda v: [[0.0]], lambda v: torch.zeros(b, n, n), "m", "a list"),
    ]:
        view = custom_map([(mine, fm_m), (theirs, fm_t)]).view(agent, rel)
        with pytest.raises(ConfigError) as e:
            view[bad]
        assert f"feature {bad!r}" in str(e.value) and what in str(e.value)
    good = custom_map([(mine, lambda v: torch.ones(b, n, 1)), (theirs, lambda v: torch.ones(b, n, n))]).view(agent, rel)
    assert good["m"].shape == (b, n, 1) and good["t"].shape == (b, n, n)


@pytest.mark.parametrize("name,target,needle", [
    ("nancost", "bad.NanCost", "cost() of a zero action from reset()'s first state is nan"),
    ("moving", "bad.NanWhenMoving", "before any update, so not from the learning rate: task moving's cost"),
])
def test_a_non_finite_cost_names_the_task_not_the_learning_rate(tmp_path, name, target, needle):
    cd = _own_tasks(tmp_path, **{name: target})
    line = one_line(run(["train", *cd, f"task={name}", "budget=tiny", "plots=false", "threads=1"], tmp_path,
                        check=False))
    assert needle in line and "optim.lr" not in line, line
    assert not list(tmp_path.rglob("model.pt"))


def test_a_yaml_value_of_the_wrong_type_names_its_key(tmp_path):
    cd = _own_tasks(tmp_path)
    (tmp_path / "conf" / "task" / "typo.yaml").write_text("_target_: ring.RingTask\nname: typo\nradius: abc\n")
    line = one_line(run(["train", *cd, "task=typo", "budget=tiny"], tmp_path, check=False))
    assert "task.radius takes a float, not 'abc'" in line and "task typo's YAML" in line


@pytest.mark.parametrize("target,near", [("ring.RingTsk", "'ring.RingTask'"), ("rnig.RingTask", "'ring'"),
                                         ("neurosym_cli.tasks.random_gird.RandomGridTask",
                                          "'neurosym_cli.tasks.random_grid'")])
def test_a_target_typo_gets_did_you_mean(tmp_path, target, near):
    cd = _own_tasks(tmp_path, typo=target)
    line = one_line(run(["train", *cd, "task=typo", "budget=tiny"], tmp_path, check=False))
    assert f"did you mean {near}?" in line, line
