"""One word per communication degree, in every table, log line, plot and document (stdlib only).

Per step (and round), agent i hears in_i others and is heard by out_i others. The measures:

    max in       max_i in_i              the most agents one agent hears (a K-rule program: at most K)
    max out      max_i out_i             the most agents that hear one agent
    max in+out   max_i (in_i + out_i)    the paper's deg (section 2); the synthesis objective's term (paper form)
    mean in+out  mean_i (in_i + out_i)   twice the links per agent

Evaluations average each over the steps (and rounds) of an episode, then over episodes and seeds; the synthesis
objective averages max in+out over the states of its dataset D (``synth.objective=hinge``: the reference's
relu(max in - K) + relu(max out - K) instead; ``scaled``: both terms in the dataset's own scales).
"""

from __future__ import annotations

from dataclasses import dataclass

from .errors import UserError

METRICS = ("cost", "max_in", "max_out", "max_degree", "mean_degree")
"""the metrics of every task and baseline, in every evaluation (rollout.py computes them; a task adds its own,
``Task.metrics``)"""

BANDWIDTH = ("bits", "link_share")
"""what the degrees cost in messages, in every evaluation since issue 40 (rollout.py computes them beside the
degrees); a record written before lacks them and reads without them (its tables show '-')

    bits         messages agent i hears in a step (every round) x message width D x FLOAT_BITS, mean over agents
    link_share   links used / N (N - 1) possible directed links, per round, mean over rounds

Both follow from mean in+out: an agent hears as many messages as it sends on average, links / N per round, so
bits = rounds x (mean in+out / 2) x D x 32 and link_share = mean in+out / (2 (N - 1)) (0 for one agent)."""

FLOAT_BITS = 32
"""bits of one float of a message (float32)"""

NAMES = {"max_in": "max in", "max_out": "max out", "max_degree": "max in+out", "mean_degree": "mean in+out",
         "bits": "bits/agent/step", "link_share": "link share"}
"""metric key -> its word (table headers, log lines, axis labels)"""

LEGEND = ("max in / max out: the most agents one agent hears / is heard by; max in+out: the most of one agent's "
          "in + out (the paper's deg); mean in+out: in + out averaged over agents; each per step, averaged over "
          "the episode")
"""the one line under every table that shows degrees"""

BANDWIDTH_LEGEND = ("bits/agent/step: messages one agent hears per step, every round, x the message width D x 32 "
                    "(float32); link share: directed links used / N (N - 1) possible; each averaged over agents and "
                    "steps")
"""the line under every table that shows bits and link share"""


def bandwidth(mean_degree, *, agents: int, rounds: int, width: int):
    """(bits, link_share) from mean in+out averaged over ``rounds`` rounds among ``agents`` agents, messages of
    ``width`` floats (see BANDWIDTH); works on numbers and on tensors alike."""
    heard = mean_degree / 2  # mean over agents of the in-degree: links / N
    share = mean_degree / (2 * (agents - 1)) if agents > 1 else mean_degree * 0
    return heard * rounds * width * FLOAT_BITS, share


@dataclass(frozen=True)
class Objective:
    """One form of the synthesis objective (``synth.objective``): what its degree term counts and whether its two
    terms are stated in the dataset's own scales (synth/objective.py computes it; docs/fidelity.md, 'Trade-off')."""

    name: str
    hinge: bool
    """the degree term is the reference's relu(max in - K) + relu(max out - K), else max_i (in_i + out_i)"""
    scaled: bool
    """L1 / L1(silence on D) + lam * degree / (2K): silence scores 1 whatever the task's action units"""
    help: str

    @property
    def term(self) -> str:
        """The word for its degree term."""
        return "K-excess" if self.hinge else "max in+out"

    @property
    def legend(self) -> str:
        """One line saying what its degree term is (and its scales)."""
        if self.hinge:
            return "K-excess: relu(max in - K) + relu(max out - K) on the synthesis dataset D, mean over its states"
        line = "max in+out: the program's max_i (in_i + out_i) on the synthesis dataset D, mean over its states"
        if self.scaled:
            line += ("; L1 is divided by silence's L1 on D and max in+out by 2K (what K rules reach when every agent "
                     "hears K and is heard by K): silence scores 1")
        return line

    def total(self, l1: float, degree: float, lam: float, scale: tuple[float, float]) -> float:
        """The objective from its terms; ``scale`` = (L1 of silence on D, reference degree 2K), read if scaled."""
        if self.scaled:
            return l1 / scale[0] + lam * degree / scale[1]
        return l1 + lam * degree

    def formula(self, l1: float, degree: float, lam: float, scale: tuple[float, float]) -> str:
        """'L1 ... + lam x term ...' as the program header and show-program print it."""
        if self.scaled:
            return (f"L1 {l1:.4f} / silence {scale[0]:.4f} + {lam:g} x {self.term} {degree:.4f} / "
                    f"{scale[1]:g}")
        return f"L1 {l1:.4f} + {lam:g} x {self.term} {degree:.4f}"


OBJECTIVES = {o.name: o for o in (
    Objective("paper", hinge=False, scaled=False, help="L1 + lam x max in+out, in the task's action units (paper "
              "section 3.4)"),
    Objective("hinge", hinge=True, scaled=False, help="L1 + lam x (relu(max in - K) + relu(max out - K)) (the "
              "reference's)"),
    Objective("scaled", hinge=False, scaled=True, help="L1 / L1(silence) + lam x max in+out / 2K: the trade-off in "
              "the task's own units, one lam for every task"),
)}
"""synth.objective -> its form"""


def objective_form(objective: str) -> Objective:
    """The form of ``synth.objective``; one line naming the choices for another name."""
    if objective not in OBJECTIVES:
        raise UserError(f"synth.objective={objective!r} is not one of {', '.join(OBJECTIVES)}")
    return OBJECTIVES[objective]


def objective_term(objective: str) -> str:
    """The word for the synthesis objective's degree term under ``synth.objective``."""
    return objective_form(objective).term


def objective_legend(objective: str) -> str:
    """One line saying what the objective's degree term is."""
    return objective_form(objective).legend


LAM_GRIDS = {"paper": [0.3, 0.5, 0.7, 1.0], "hinge": [0.3, 0.5, 0.7, 1.0], "scaled": [0.1, 0.25, 0.5, 0.75]}
"""select.lam when it is empty, by synth.objective: lam means another thing in each objective's units. paper and
hinge: the paper's grid (appendix B), in the task's action units; scaled: shares of silence's action gap per 2K of
degree around its default 0.25, below 1 (at lam >= 1 no program of degree 2K beats silence; docs/fidelity.md)"""
