"""Schemes from outside the package (neurosym_cli/schemes/registry.py): the example (examples/schemes/random_k.py)
by an installed entry point and by ``baseline._target_`` through train, eval, a joblib sweep and the pipeline; the
registry's one-line refusals."""

import json
import os
import shutil
import subprocess

import pytest

from conftest import ROOT, neurosym_cmd
from neurosym_cli.errors import ConfigError
from neurosym_cli.schemes import SCHEMES, registry
from plugin_schemes import EXAMPLE_DIR

TINY = ["task=random-cross", "budget=tiny", "plots=false", "threads=1"]


def _run(args, cwd, env=None):
    env = {**os.environ, "NEUROSYM_RUNS": str(cwd), **(env or {})}
    env.pop(registry.TARGETS_ENV, None)
    return subprocess.run([*neurosym_cmd(), *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def _installed(tmp_path, entry_points: str) -> dict:
    """The environment of a process in which a distribution offers ``entry_points`` in neurosym.schemes, its module
    being examples/schemes/random_k.py (what `pip install -e examples/schemes` makes)."""
    dist = tmp_path / "site" / "randomk-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: randomk\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(f"[{registry.ENTRY_POINTS}]\n{entry_points}\n")
    return {"PYTHONPATH": os.pathsep.join([str(tmp_path / "site"), str(EXAMPLE_DIR),
                                           os.environ.get("PYTHONPATH", "")])}


def _metrics(tmp_path, label):
    return json.loads((tmp_path / "random-cross" / "tiny" / "seed0" / "eval" / label / "metrics.json").read_text())


def test_a_scheme_by_entry_point_trains_and_evaluates_like_a_built_in_one(tmp_path):
    env = _installed(tmp_path, "random-k = random_k:RandomK")
    p = _run(["--help"], tmp_path, env)
    assert p.returncode == 0 and "random-k" in p.stdout and "drawn at random" in p.stdout
    for verb in ("train", "eval"):
        p = _run([verb, *TINY, "baseline=random-k", "baseline.k=3"], tmp_path, env)
        assert p.returncode == 0, p.stderr
    m = _metrics(tmp_path, "random-k-k3")
    assert m["baseline"] == "random-k" and m["summary"]["max_in"]["mean"] == pytest.approx(3.0)
    assert (tmp_path / "random-cross" / "tiny" / "seed0" / "train" / "random-k-k3" / "model.pt").exists()
    p = _run(["eval", *TINY, "baseline=random-k", "baseline.kk=3"], tmp_path, env)  # its own keys are checked
    assert p.returncode == 2 and "did you mean 'baseline.k'?" in p.stderr


def test_a_scheme_by_target_runs_in_a_joblib_sweep_and_the_pipeline(tmp_path):
    shutil.copy(EXAMPLE_DIR / "random_k.py", tmp_path / "random_k.py")  # the user's module, in the working directory
    target = "baseline._target_=random_k.RandomK"
    p = _run(["train", "-m", *TINY, target, "seed=0,1", "hydra/launcher=joblib", "hydra.launcher.n_jobs=2"], tmp_path)
    assert p.returncode == 0, p.stderr  # each joblib worker resolves the class again (NEUROSYM_SCHEMES)
    for seed in (0, 1):
        assert (tmp_path / "random-cross" / "tiny" / f"seed{seed}" / "train" / "random-k-k2" / "model.pt").exists()
    p = _run(["pipeline", *TINY, target, "baselines=[no-comm,random-k]"], tmp_path)
    assert p.returncode == 0, p.stderr
    assert "random-k-k2" in p.stdout and _metrics(tmp_path, "random-k-k2")["baseline"] == "random-k"
    p = _run(["eval", *TINY, "baseline=random-k"], tmp_path)  # without the target, nothing registers it
    assert p.returncode == 2 and "unknown baseline 'random-k'" in p.stderr and "baseline._target_" in p.stderr


def test_a_broken_plugin_is_left_out_and_one_line_when_named(tmp_path):
    env = _installed(tmp_path, "gone = random_k:RandomKey\ndist = random_k:RandomK")
    helped = _run(["--help"], tmp_path, env)  # the rest of the CLI works, and says why they are not usable
    assert helped.returncode == 0 and "not usable" in helped.stdout, helped.stderr
    assert "gone" in helped.stdout and "takes the name 'dist' of a built-in scheme" in helped.stdout
    assert "  dist                a transformer trained and run hearing its k" in helped.stdout  # the built-in kept
    p = _run(["train", *TINY, "baseline=gone"], tmp_path, env)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2 and len(lines) == 1 and "has no 'RandomKey'; did you mean 'random_k.RandomK'?" in lines[0]


def test_the_registry_refuses_what_breaks_the_contract(monkeypatch):
    from dataclasses import dataclass

    from neurosym_cli.baselines import BaselineConfig
    from neurosym_cli.schemes.families import OwnRule

    @dataclass
    class NoRule(BaselineConfig):
        """answers nothing"""
        name: str = "no-rule"

    @dataclass
    class Nameless(OwnRule):
        pass

    with pytest.raises(ConfigError, match=r"answers none of model_dir\(\), weights\(\), upstream\(\), command\(\)"):
        registry.register(registry.made(NoRule, None, "t"), "t")
    with pytest.raises(ConfigError, match="has a name that is missing"):
        registry.register(registry.made(Nameless, None, "t"), "t")
    with pytest.raises(ConfigError, match="has no description"):
        registry.register(registry.made(Nameless, "nameless", "t"), "t")
    with pytest.raises(ConfigError, match="does not extend"):
        registry.made(dict, "d", "t")
    with pytest.raises(ConfigError, match="takes the name 'expo' of a built-in scheme"):
        registry.register(registry.made(Nameless, "expo", "t").__class__("expo", "other words"), "t")
    assert registry.made(NoRule, None, "t").pipeline is False  # a plugin joins the pipeline only when named
    monkeypatch.delenv(registry.TARGETS_ENV, raising=False)  # restored after the test, as SCHEMES below
    monkeypatch.syspath_prepend(str(EXAMPLE_DIR))
    monkeypatch.setitem(SCHEMES, "random-k", None)  # taken out again after the test
    del SCHEMES["random-k"]
    _, bad = registry.targets_in(["baseline._target_=neurosym_cli.schemes.expo.Expo"])  # no default name
    assert "has a name that is missing; give the class a default name" in bad
    args, bad = registry.targets_in(["seed=1", "+baseline._target_=random_k:RandomK", "baseline.k=4"])
    assert bad is None and args == ["seed=1", "baseline.k=4", "baseline=random-k"]
    assert os.environ[registry.TARGETS_ENV] == "random_k:RandomK"  # what the command's workers register
    _, bad = registry.targets_in(["baseline=dist", "baseline._target_=random_k.RandomK"])
    assert "names random-k while baseline= names dist; name one scheme" in bad
    _, bad = registry.targets_in(["baseline._target_=a.B,c.D"])
    assert bad.startswith("baseline._target_=a.B,c.D: one class per command line")
