"""One word per communication degree, in every table, log line, plot and document (stdlib only).

Per step (and round), agent i hears in_i others and is heard by out_i others. The measures:

    max in       max_i in_i              the most agents one agent hears (a K-rule program: at most K)
    max out      max_i out_i             the most agents that hear one agent
    max in+out   max_i (in_i + out_i)    the paper's deg (section 2); the synthesis objective's term (paper form)
    mean in+out  mean_i (in_i + out_i)   twice the links per agent

Evaluations average each over the steps (and rounds) of an episode, then over episodes and seeds; the synthesis
objective averages max in+out over the states of its dataset D (``synth.objective=hinge``: the reference's
relu(max in - K) + relu(max out - K) instead).
"""

from __future__ import annotations

NAMES = {"max_in": "max in", "max_out": "max out", "max_degree": "max in+out", "mean_degree": "mean in+out"}
"""metric key -> its word (table headers, log lines, axis labels)"""

LEGEND = ("max in / max out: the most agents one agent hears / is heard by; max in+out: the most of one agent's "
          "in + out (the paper's deg); mean in+out: in + out averaged over agents; each per step, averaged over "
          "the episode")
"""the one line under every table that shows degrees"""


def objective_term(objective: str) -> str:
    """The word for the synthesis objective's degree term under ``synth.objective``."""
    return "max in+out" if objective == "paper" else "K-excess"


def objective_legend(objective: str) -> str:
    """One line saying what the objective's degree term is."""
    if objective == "paper":
        return "max in+out: the program's max_i (in_i + out_i) on the synthesis dataset D, mean over its states"
    return "K-excess: relu(max in - K) + relu(max out - K) on the synthesis dataset D, mean over its states"
