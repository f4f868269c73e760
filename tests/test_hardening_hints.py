"""Issue 38, input accepted without a word and hints that send the user round in circles: grids with a value twice,
render and figures beyond the episode, booleans other than true and false, numbers in other digits, a chain of
missing stages, a bare report beside another task's results, and one exit status for every config error."""

import shlex

import pytest

from conftest import run_dir
from test_plugins import one_line, run

TINY = ["task=two-groups-cross", "budget=tiny", "threads=1", "plots=false"]


@pytest.fixture(scope="module")
def oracle_run(tmp_path_factory):
    """A runs root with two-groups-cross's tiny oracle trained and evaluated (tf-full): nothing else."""
    root = tmp_path_factory.mktemp("hints")
    run(["train", *TINY], root)
    run(["eval", *TINY], root)
    return root


@pytest.mark.parametrize("verb, grid, key, value", [
    ("select", "select.lam=[0.3,0.3]", "select.lam", "0.3"),
    ("select", "select.lam=[0.3,0.30000001]", "select.lam", "0.3"),  # both would be named lam0.3
    ("select", "select.rules=[2,3,2]", "select.rules", "2"),
    ("select", "select.features=[v1,v1]", "select.features", "v1"),
    ("rl", "rl.grid_cost=[0.1,0.1]", "rl.grid_cost", "0.1"),
    ("rl", "rl.grid_shaped=[true,true]", "rl.grid_shaped", "true"),
    ("rl", "rl.grid_init=[oracle,oracle]", "rl.grid_init", "oracle"),
])
def test_a_grid_value_listed_twice_is_one_line(tmp_path, verb, grid, key, value):
    """Two jobs of one grid point wrote one run directory at once: the second stopped on the first's lock with a
    message about another process, after the first had searched or trained."""
    p = run([verb, *TINY, grid], tmp_path, check=False)
    line = one_line(p)
    assert p.returncode == 2 and f"{key} lists {value} twice" in line and "once" in line, line
    assert not (tmp_path / "two-groups-cross").exists()  # nothing ran


def test_figures_refuse_an_agent_or_a_step_beyond_the_episode(oracle_run):
    """render.agent=500 and render.step=9999 were clamped to the last agent and step without a word."""
    figures = oracle_run / "two-groups-cross/tiny/seed0/figures"
    for args, needle in ((["render.agent=500"], "render.agent=500, but episode 0 has 10 agents; choose "
                                                "render.agent=0..9"),
                         (["render.step=9999"], "render.step=9999, but episode 0 has 8 steps; choose "
                                                "render.step=0..7")):
        p = run(["figures", *TINY, "render.baselines=[tf-full]", *args], oracle_run, check=False)
        assert p.returncode == 2 and needle in one_line(p), p.stderr
        assert not figures.exists() or not any(figures.iterdir())  # nothing drawn before the refusal
    p = run(["figures", *TINY, "render.baselines=[tf-full]", "render.agent=9", "render.step=7"], oracle_run)
    tag = run_dir("synth", oracle_run, *TINY).program_tag  # the figures are named after the run's program
    assert (figures / f"attention-{tag}-episode0.png").is_file()  # the last agent and step are drawn


def test_render_refuses_an_episode_beyond_the_evaluation(oracle_run):
    """`render episode=99` drew an episode of an evaluation seed no evaluation ran (tiny: 2 seeds of 3)."""
    for verb in ("render", "figures"):
        p = run([verb, *TINY, "episode=99"], oracle_run, check=False)
        line = one_line(p)
        assert p.returncode == 2 and "episode=99 is beyond the evaluation's 6 episodes" in line, line
        assert "choose episode=0..5" in line
    assert not (oracle_run / "two-groups-cross/tiny/seed0/render").exists()
    run(["render", *TINY, "baseline=tf-full", "episode=5"], oracle_run)  # the last one is drawn


@pytest.mark.parametrize("value", ["yes", "no", "on", "off", "1", "0"])
def test_booleans_are_true_or_false_only(tmp_path, value):
    """`overwrite=yes` was read as true here while elsewhere only true and false were named."""
    line = one_line(run(["eval", *TINY, f"overwrite={value}"], tmp_path, check=False))
    assert f"overwrite takes true or false, not '{value}'" in line, line


def test_true_and_false_in_any_case_still_pass_the_check():
    from neurosym_cli.overrides import check

    assert check(["overwrite=true", "overwrite=False", "plots=TRUE", "rl.grid_shaped=[true,false]"]) is None
    assert "true or false" in check(["rl.grid_shaped=[true,yes]"])


@pytest.mark.parametrize("arg, fix", [
    ("lam=０.５", "write lam=0.5"),  # fullwidth digits and point
    ("lam=½", "write lam=0.5"),
    ("lam=1½", "write lam=1.5"),
    ("lam=0,5", "write lam=0.5"),  # a decimal comma (outside -m a comma was only a sweep)
    ("lam=٠٫٥", "write lam=0.5"),  # Arabic-Indic digits and decimal separator
    ("rules=٣", "write rules=3"),
    ("lam='０.５'", "write lam=0.5"),  # quoted, it passed as a text
    ("select.lam=[０.３,0.5]", "write select.lam=[0.3,0.5]"),
    ("lam=é", "e.g. lam=0.5"),
])
def test_a_number_in_other_digits_names_how_to_write_it(tmp_path, arg, fix):
    """The hint on how to write a non-ASCII number was lost behind Hydra's grammar error ("cannot read '０.５' at
    '０'")."""
    p = run(["eval", *TINY, arg], tmp_path, check=False)
    line = one_line(p)
    assert p.returncode == 2 and "written in ASCII digits" in line and fix in line, line


def test_several_missing_stages_are_named_at_once_with_the_pipeline_that_runs_them(tmp_path):
    """eval before train pointed back one stage at a time: retrain, then (after it) synth, then train."""
    line = one_line(run(["eval", *TINY, "baseline=prog-retrained"], tmp_path, check=False))
    assert "prog-retrained needs 3 stages that have not run" in line, line
    train, synth, retrain = (line.index(f"`neurosym {verb} ") for verb in ("train", "synth", "retrain"))
    assert train < synth < retrain, line
    line = one_line(run(["retrain", *TINY], tmp_path, check=False))
    assert "retrain of prog-retrained needs 2 stages" in line and "`neurosym retrain " not in line, line
    pipeline = line.split("; or `", 1)[1].split("`", 1)[0]
    assert pipeline.startswith("neurosym pipeline ") and "baselines=[prog-retrained]" in pipeline
    run([*shlex.split(pipeline)[1:], "threads=1", "plots=false"], tmp_path)  # runs as printed
    # ... and makes what retrain and eval needed: the searched program's retraining (not the front's pick's)
    retrained = run_dir("eval", tmp_path, *TINY, "baseline=prog-retrained")
    assert (tmp_path / "two-groups-cross/tiny/seed0/eval" / retrained.label / "metrics.json").is_file()
    run(["eval", *TINY, "baseline=prog-retrained"], tmp_path)
    # one stage missing: its reader's own line, as before
    retrained.model_file.unlink()
    line = one_line(run(["eval", *TINY, "baseline=prog-retrained"], tmp_path, check=False))
    assert "no checkpoint at" in line and "create it with `neurosym retrain " in line, line


def test_a_bare_report_names_the_tasks_whose_results_are_there(oracle_run, tmp_path):
    """A bare `neurosym report` looked at the default task and said to run its pipeline, though two-groups-cross's
    results were in the runs root."""
    p = run(["report", f"runs_root={oracle_run}"], tmp_path, check=False)
    line = one_line(p)
    assert "the runs root holds others: `neurosym report task=two-groups-cross budget=tiny" in line, line
    assert "for random-cross (quick budget) run `neurosym pipeline task=random-cross" in line
    printed = line.split("`", 2)[1]
    out = run([*shlex.split(printed)[1:], "plots=false"], tmp_path)  # runs as printed, from elsewhere
    assert "tf-full" in out.stdout


def test_config_errors_exit_2_wherever_they_are_found(tmp_path):
    """`rules=0` (a schema's range) exited 1 and `rules=abc` (before Hydra) 2; a missing artifact stays 1."""
    for args in (["rules=0"], ["rules=abc"], ["task.link_failure=1.0"], ["select.lam=[0.3,0.3]"], ["episode=-1"]):
        p = run(["eval", *TINY, *args], tmp_path, check=False)
        one_line(p)
        assert p.returncode == 2, (args, p.stderr)
    p = run(["eval", *TINY], tmp_path, check=False)  # no oracle: an artifact, not the config
    assert p.returncode == 1 and "no checkpoint at" in one_line(p)
