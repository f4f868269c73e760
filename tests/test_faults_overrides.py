"""Faults and hostile input, overrides: typos, types, ranges, interpolations, removals, huge numbers, long values,
the Python API's errors: every bad input is one line and a non-zero exit, and no result is lost silently.
docs/reliability.md lists the promises and what tests each; the other classes of fault are the other
tests/test_faults_*.py files (shared helpers: tests/fault_helpers.py)."""

import os

import pytest

from fault_helpers import TINY, one_line_error, run
from neurosym_cli.config import ConfigError


# ------------------------------------------------------------------------------------------ overrides
@pytest.mark.parametrize("arg,needle", [
    ("seeed=1", "did you mean 'seed'"), ("lamda=0.3", "did you mean 'lam'"), ("+foo=1", "unknown key 'foo'"),
    ("task.colision_weight=3", "did you mean 'task.collision_weight'"), ("seed=abc", "takes an integer"),
    ("lam=0.3,abc", "takes a number"), ("overwrite=maybe", "takes true or false"),
    ("runs_root=\u00e9t\u00e9", "only in quotes"),
])
def test_bad_overrides_are_named(arg, needle):
    from neurosym_cli.overrides import check
    from neurosym_cli.tasks.random_cross import CrossConfig  # the task's own keys come from its schema

    assert needle in (check(["-m", arg], [CrossConfig]) or "")


@pytest.mark.parametrize("arg,needle", [("seeed=1", "did you mean 'seed'"), ("seed=abc", "takes an integer"),
                                        ("rules=1000", "at most 40 - 1"), ("threads=999", "CPU")])
def test_bad_overrides_are_one_line(tmp_path, arg, needle):
    one_line_error(run(["train", arg], tmp_path, check=False), needle)


def test_good_overrides_pass_the_check():
    from neurosym_cli.overrides import check
    from neurosym_cli.tasks.random_cross import CrossConfig  # task.num_groups is a key of the cross tasks' schema

    assert check(["seed=0,1,2", "lam=0.3,0.5", "budget.horizon=null", "task.num_groups=2", "hydra/launcher=joblib",
                  "hydra.launcher.n_jobs=2", "baselines=[tf-full,prog]", "seed=range(0,3)", "-m", "--cfg", "job",
                  "runs_root='\u00e9t\u00e9'", "synth.backend=torch", "+seed=3"], [CrossConfig]) is None


def test_rules_and_threads_ranges_in_the_schema():
    from neurosym_cli.commands.apps import compose_config

    with pytest.raises(ConfigError, match="rules=30"):
        compose_config("train", ["task=random-grid", "rules=30"])
    assert compose_config("train", ["task=random-grid", "rules=29"]).rules == 29


def test_unwritable_system_path_is_one_line(tmp_path):
    one_line_error(run(["train", "runs_root=/proc/neurosym"], tmp_path, check=False), "cannot write")


@pytest.mark.parametrize("arg,needle", [
    ("seed=${oops}", "${oops} names no key of the config"),
    ("rules=${task.rulez}", "did you mean ${task.rules}?"),
    ("seed=${oc.env:NEUROSYM_SURELY_UNSET}", "NEUROSYM_SURELY_UNSET is not set; set it, or give a default"),
    ("~task", "task cannot be removed"),
    ("~budget", "budget cannot be removed"),
    ("~seed", "seed cannot be removed"),
    ("seed=99999999999999999999", "beyond a 64-bit integer"),
    ("seed=-9223372036854775809", "beyond a 64-bit integer"),
    ("task.v_max=1e308", "task.v_max must lie in"),
    ("hydra.run.dir=${oops}", "Interpolation key 'oops' not found"),  # past our check: Hydra's own, one line
])
def test_interpolations_removals_and_huge_numbers_in_overrides_are_one_line(tmp_path, arg, needle):
    one_line_error(run(["train", *TINY, arg], tmp_path, check=False), needle)
    assert not list(tmp_path.rglob("model.pt"))


@pytest.mark.parametrize("arg", ["task=random-gird", "baseline=tf-ful", "hydra/launcher=nope", "seed=${oops}",
                                 "+foo=1"])
def test_the_python_api_raises_the_console_scripts_line(tmp_path, arg):
    """`ns.compose` refuses bad input with the very line `neurosym train` prints (not Hydra's "Could not find")."""
    import neurosym_cli.api as ns
    from neurosym_cli.errors import UserError

    with pytest.raises(UserError) as e:
        ns.compose("train", [arg, "budget=tiny"])
    p = run(["train", arg, "budget=tiny"], tmp_path, check=False)
    one_line_error(p, str(e.value))
    assert p.stderr.strip() == f"neurosym train: error: {e.value}"


def test_working_interpolations_still_work(tmp_path):
    from neurosym_cli.overrides import check

    os.environ.setdefault("NEUROSYM_RUNS", str(tmp_path))
    assert check(["rules=${task.rules}", "runs_root=${oc.env:NEUROSYM_RUNS}", "seed=${oc.env:NOPE_NOPE,3}",
                  "seed=9223372036854775807"]) is None


@pytest.mark.parametrize("arg", ["lam=" + "9" * 20_000 + "x", "task.name=" + "x" * 20_000, "x" * 20_000 + "=1",
                                 "runs_root=\u00e9" + "x" * 20_000])
def test_long_values_are_cut_in_messages(tmp_path, arg):
    """Issue 28, item 4: a 20,000-character value is quoted in part, with its length; a name that long is refused
    (names are at most 100 characters)."""
    p = run(["train", *TINY, arg], tmp_path, check=False)
    assert p.returncode != 0 and "Traceback" not in p.stderr
    assert len(p.stderr) < 1_000 and "characters)" in p.stderr, p.stderr[:2000]


def test_the_error_edge_cuts_every_long_word():
    from neurosym_cli.errors import cut, cut_words

    msg = cut_words("cannot read " + "/a" * 10_000 + ": gone")
    assert len(msg) < 300 and msg.endswith("... (20,001 characters) gone")  # the word with its colon
    assert cut("short") == "short"
