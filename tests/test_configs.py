"""Every conf/ file composes and converts to its typed schema; bad values fail with clear errors."""

from pathlib import Path

import pytest
from hydra import compose, initialize_config_module

import neurosym_cli.commands.apps  # noqa: F401  (registers the schema)
from conftest import PAPER_METHOD
from neurosym_cli.schemes import SCHEMES as BASELINES
from neurosym_cli.config import ConfigError, RunConfig
from neurosym_cli.commands._run import typed_config
from neurosym_cli.tasks import task_class

CONF = Path(__file__).resolve().parents[1] / "conf"
GROUPS = {g: sorted(p.stem for p in (CONF / g).glob("*.yaml")) for g in ("task", "budget")} | {"baseline": list(BASELINES)}
COMMANDS = ["train", "eval"]


def _compose(cmd, overrides=()):
    with initialize_config_module("neurosym_cli.conf", version_base="1.3"):
        return compose(cmd, overrides=list(overrides))


@pytest.mark.parametrize("cmd", COMMANDS)
@pytest.mark.parametrize("group,option", [(g, o) for g, opts in GROUPS.items() for o in opts])
def test_every_option_composes_and_types(cmd, group, option):
    cfg = _compose(cmd, [f"{group}={option}"])
    typed = typed_config(cfg)
    assert isinstance(typed, RunConfig)
    assert typed.cmd == cmd
    assert getattr(typed, group).name == option
    assert task_class(typed.task._target_) is not None  # every task YAML names an importable task class


def test_task_defaults_follow_the_paper():
    for task, rules, lam in [("random-cross", 5, 0.5), ("random-grid", 2, 0.5), ("unlabeled-goals", 5, 0.7)]:
        typed = typed_config(_compose("train", [f"task={task}"]))
        assert (typed.rules, typed.lam) == (rules, lam)
    typed = typed_config(_compose("train", ["task=random-grid", "rules=4"]))
    assert typed.rules == 4
    assert typed_config(_compose("train", ["task=unlabeled-goals"])).task.rounds == 2


def test_exp_dir_is_stable_and_keyed():
    cfg = _compose("train", ["task=random-grid", "seed=3", "budget=tiny", "runs_root=/r"])
    assert cfg.exp_dir == "/r/random-grid/tiny/seed3"


@pytest.mark.parametrize("override", ["budget.train_rollouts=-5", "budget.eval_seeds=0", "rules=0", "device=tpu",
                                      "optim.gamma=1.5"])
def test_out_of_range_values_are_config_errors(override):
    cfg = _compose("train", [override])
    with pytest.raises(ConfigError):
        typed_config(cfg)


def test_wrongly_typed_override_fails_at_compose():
    with pytest.raises(Exception, match="train_rollouts"):
        _compose("train", ["budget.train_rollouts=abc"])


def test_paper_budget():
    b = typed_config(_compose("train", ["budget=paper"])).budget
    assert (b.train_rollouts, b.eval_seeds) == (10_000, 20)


def test_hinge_programs_do_not_share_the_paper_objectives_place():
    from neurosym_cli.run import RunDir, synth_command

    # the paper's method (PAPER_METHOD): the objective's suffix alone, without the default hybrid search's
    paper = typed_config(_compose("synth", ["task=random-grid", "baseline=prog", *PAPER_METHOD]))
    hinge = typed_config(_compose("synth", ["task=random-grid", "baseline=prog", "synth.objective=hinge",
                                            *PAPER_METHOD]))
    assert RunDir(paper).program_tag == "k2-lam0.5-v1" and RunDir(hinge).program_tag == "k2-lam0.5-v1-hinge"
    assert RunDir(paper).synth_dir != RunDir(hinge).synth_dir
    assert "synth.objective=hinge" in synth_command(hinge)


def test_baseline_group_is_the_registry():
    """conf/ holds no baseline files: the group's options are the registry's entries, with their fields."""
    assert not (CONF / "baseline").exists()
    for name, b in BASELINES.items():
        typed = typed_config(_compose("eval", [f"baseline={name}"]))
        assert typed.baseline == b
    assert typed_config(_compose("pipeline")).baselines == [n for n, b in BASELINES.items() if b.pipeline]
