"""The baselines of the paper (section 4 and appendix B), listed once (stdlib only, so `neurosym --help` stays fast).

A baseline is the shared transformer plus a communication provider that hands it a mask (``comm``) and the
weights it runs on (``model``). Everything else is derived from this list: the config group ``baseline=``
(registered in Hydra's ConfigStore by ``commands/apps.py``), the pipeline's stage graph (``stages/graph.py``),
the order of every results table, the default of ``baselines=`` and the lists in ``neurosym --help``.
"""

from __future__ import annotations

from .config import BaselineConfig

BASELINES: dict[str, BaselineConfig] = {b.name: b for b in (
    BaselineConfig("tf-full", "full", model="oracle",
                   description="the oracle: soft attention over every other agent (paper section 3.1)"),
    BaselineConfig("hard-attn", "topk", model="oracle",
                   description="the oracle, each agent hears only its k = rules largest attention logits"),
    BaselineConfig("dist", "nearest", model="own",
                   description="a transformer trained and run hearing its k = rules nearest agents"),
    BaselineConfig("prog", "program", model="oracle",
                   description="the oracle under the synthesized program's hard attention (section 3.3)"),
    BaselineConfig("prog-retrained", "program", model="retrained",
                   description="the full method: the oracle retrained under the program (section 3.5)"),
    BaselineConfig("det-prog", "program", det=True, model="oracle",
                   description="like prog, with argmax rules only (appendix B)"),
    BaselineConfig("det-prog-retrained", "program", det=True, model="retrained",
                   description="det-prog with the oracle retrained under it (appendix B)"),
    BaselineConfig("dt", "tree", model="oracle",
                   description="the oracle under a decision tree imitating a degree-capped hard attention (appendix B)"),
    BaselineConfig("dt-retrained", "tree", model="retrained",
                   description="dt with the oracle retrained under the tree (appendix B)"),
    BaselineConfig("no-comm", "none", model="own",
                   description="a transformer trained and run with no communication (reference point)"),
    BaselineConfig("rl", "gated", model="own", pipeline=False,
                   description="appendix D: whom to hear as actions, by policy gradient (`neurosym rl`: rl1, rl2)"),
)}
"""name -> baseline, in the paper's order (the order of every table)."""

ORACLE = "tf-full"
"""the baseline whose training makes the oracle that hard-attn, the programs, the trees and retraining start from"""


def get(name: str) -> BaselineConfig:
    """The baseline of that name; an unknown name is a one-line error listing the choices."""
    from .config import ConfigError

    if name not in BASELINES:
        raise ConfigError(f"unknown baseline {name!r}; choose one of: {', '.join(BASELINES)}")
    return BASELINES[name]


def rank(name: str) -> int:
    """Position of a baseline in the paper's order (unknown names last)."""
    return list(BASELINES).index(name) if name in BASELINES else len(BASELINES)
