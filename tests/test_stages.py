"""The stage graph is derived from the baseline registry: what each baseline needs, in an order that runs."""

import pytest

from neurosym_cli.schemes import SCHEMES as BASELINES, get, rank
from neurosym_cli.config import ConfigError
from neurosym_cli.stages.graph import Stage, plan, requires, upstream


def test_each_baseline_needs_what_it_runs_on():
    assert upstream("tf-full") == [Stage("train", "tf-full")]
    assert upstream("hard-attn") == [Stage("train", "tf-full")]
    assert upstream("no-comm") == [Stage("train", "no-comm")]  # its own model, not the oracle
    assert upstream("prog-retrained") == [Stage("train", "tf-full"), Stage("synth", "prog"),
                                          Stage("retrain", "prog-retrained")]
    assert upstream("det-prog-retrained")[1] == Stage("synth", "det-prog")  # argmax-only programs
    assert upstream("dt-retrained")[1] == Stage("synth", "dt")


@pytest.mark.parametrize("baselines", [list(BASELINES), ["prog-retrained", "dist"], ["dt-retrained", "prog"]])
def test_plan_runs_every_stage_once_after_what_it_requires(baselines):
    stages = plan(baselines)
    assert len(stages) == len(set(stages))
    for k, s in enumerate(stages):
        assert all(dep in stages[:k] for dep in requires(s)), s
    assert [s.baseline for s in stages if s.verb == "eval"] == baselines


def test_full_plan_has_one_synth_per_search_and_one_retrain_per_retrained_baseline():
    stages = plan(list(BASELINES))
    assert sorted(s.baseline for s in stages if s.verb == "synth") == ["det-prog", "dt", "prog"]
    assert sorted(s.baseline for s in stages if s.verb == "retrain") == sorted(
        n for n, b in BASELINES.items() if b.weights().verb == "retrain")
    assert sorted(s.baseline for s in stages if s.verb == "train") == ["comm-range", "dist", "expo", "no-comm", "rl", "tf-full"]
    # rl starts from the oracle (rl.init=oracle): its training waits for the oracle's
    assert Stage("train", "tf-full") in requires(Stage("train", "rl"))
    assert stages.index(Stage("train", "tf-full")) < stages.index(Stage("train", "rl"))


def test_unknown_baseline_is_a_config_error_that_lists_the_choices():
    with pytest.raises(ConfigError, match="choose one of: tf-full, hard-attn"):
        get("tf-ful")
    with pytest.raises(ConfigError):
        plan(["prog", "nope"])
    assert rank("tf-full") == 0 and rank("comm-range") == len(BASELINES) - 1 and rank("nope") == len(BASELINES)
