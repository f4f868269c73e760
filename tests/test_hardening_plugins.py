"""Issue 38, plugins and the Python path: a user's files beside them never replace a module of Python's, their task
modules still load the documented way, and a task of their own that misbehaves is one line naming it."""

import shutil
import subprocess
import sys

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
