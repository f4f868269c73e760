"""The figures' loss axes say how the task's cost combines its agents, in the task's own words (``cost_words``):
"summed over agents" for every built-in task, what a task of one's own says otherwise."""

from __future__ import annotations

import dataclasses
import textwrap
from types import SimpleNamespace

import pytest

MEAN_TASK = '''
import ring

class MeanRing(ring.RingTask):
    cost_words = "averaged over agents"
    def cost(self, next_state, action):
        return super().cost(next_state, action) / self.n

class BadRing(ring.RingTask):
    cost_words = ""
'''


@pytest.fixture
def mean_ring(tmp_path, monkeypatch):
    from neurosym_cli.tasks.registry import add_import_paths

    from conftest import ROOT

    add_import_paths([str(ROOT / "examples" / "ring")])
    (tmp_path / "meanring.py").write_text(textwrap.dedent(MEAN_TASK))
    monkeypatch.syspath_prepend(str(tmp_path))
    from neurosym_cli.tasks.random_cross import CrossConfig

    ring = __import__("ring")
    return ring.RingConfig(_target_="meanring.MeanRing"), CrossConfig(_target_="neurosym_cli.tasks.random_cross."
                                                                        "RandomCrossTask", name="random-cross")


def test_a_task_says_how_its_cost_combines_agents(mean_ring):
    from neurosym_cli.errors import ConfigError
    from neurosym_cli.tasks.base import COST_WORDS, cost_words

    mine, builtin = mean_ring
    assert cost_words(builtin) == COST_WORDS == "summed over agents"
    assert cost_words(mine) == "averaged over agents"
    with pytest.raises(ConfigError, match="BadRing.cost_words must be one line of text"):
        cost_words(dataclasses.replace(mine, _target_="meanring.BadRing"))


def test_the_figures_loss_axes_print_the_tasks_words(mean_ring, tmp_path, monkeypatch):
    import matplotlib.axes

    from neurosym_cli.plotting import figure2, stress_plot
    from neurosym_cli.tasks.base import cost_words

    labels: list[str] = []
    for setter in ("set_xlabel", "set_ylabel"):
        orig = getattr(matplotlib.axes.Axes, setter)
        monkeypatch.setattr(matplotlib.axes.Axes, setter,
                            lambda self, text, *a, orig=orig, **k: (labels.append(text), orig(self, text, *a, **k))[1])
    stat = {"mean": 1.0, "std": 0.1, "ci95": 0.1}
    row = {"cost": stat, "max_in": stat, "max_out": stat}
    words = cost_words(mean_ring[0])
    figure2([("tf-full", row), ("no-comm", row)], "t", tmp_path / "f2.png", cost_words=words)
    cfg = SimpleNamespace(rules=2, seed=0, task=mean_ring[0], budget=SimpleNamespace(name="tiny"),
                          stress=SimpleNamespace(seeds=2))
    stress_plot([{"axis": "failure", "label": "tf-full", "link_failure": 0.0, "max_agents": 8, **row}], cfg,
                tmp_path / "stress.png", words)
    figure2([("tf-full", row)], "t", tmp_path / "f2-default.png")
    loss = [t for t in labels if t.startswith("loss (")]  # panel (c) is "loss" alone
    assert loss == ["loss (time-averaged, averaged over agents; lower is better)",
                    "loss (averaged over agents; lower is better)",
                    "loss (time-averaged, summed over agents; lower is better)"], loss
