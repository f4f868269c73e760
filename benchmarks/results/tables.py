"""The arithmetic and the formatting every table of the page uses: means, paired intervals, verdicts, and the
committed programs as the page shows them."""

from __future__ import annotations

import functools

from neurosym_cli.dsl import parse
from neurosym_cli.stats import mean_ci, t95  # one Student-t interval for the page and `select`

EVAL_PM = "mean ± 95 % Student-t half-width over the evaluation seeds (the episode noise of one trained model)"
"""what ± means in every table of one training seed's evaluation (``ms``)"""


def mean(v: dict, b: str, k: str = "cost") -> float:
    """Baseline ``b``'s mean of metric ``k`` over the evaluation seeds of variant ``v``."""
    return v["baselines"][b]["summary"][k]["mean"]


def ms(v: dict, b: str, k: str, digits: int = 2) -> str:
    """A baseline's metric over the evaluation seeds as the tables write it: mean ± 95 % t half-width (EVAL_PM)."""
    s = v["baselines"][b]["summary"][k]
    half = t95(v["seeds"]) * s["std"] / v["seeds"] ** 0.5
    return f"{s['mean']:.{digits}f} ± {half:.{digits}f}"


def paired(v: dict, a: str, b: str) -> tuple[float, float]:
    """Mean and 95% half-width of a - b over the evaluation seeds both share."""
    xa, xb = v["baselines"][a]["cost_per_seed"], v["baselines"][b]["cost_per_seed"]
    return mean_ci([xa[s] - xb[s] for s in sorted(set(xa) & set(xb), key=int)])


def minus(text: str) -> str:
    """Text with its minus signs written as true minus signs (as the document writes signed numbers)."""
    return text.replace("-", "−")


def pm(x: tuple[float, float], digits: int = 2) -> str:
    """A paired difference as the document writes it: signed, with a true minus sign."""
    return minus(f"{x[0]:+.{digits}f} ± {x[1]:.{digits}f}")


def gap(v: dict, a: str, b: str) -> float:
    """Relative loss difference of a against b, in percent."""
    return (mean(v, a) - mean(v, b)) / mean(v, b) * 100


def verdict(ok: bool) -> str:
    return "**supported**" if ok else "**not supported**"


@functools.lru_cache(maxsize=None)
def vocab(task: str, features: str):
    """The declared features of a task (their words make the readings), from its config as `neurosym` composes it."""
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.tasks import make_task

    cfg = compose_config("show_program", [f"task={task}", f"features={features}"])
    return make_task(cfg.task).features(features).vocab


def shown(text: str, task: str, features: str, objective: str = "paper"):
    """A committed program as the page shows it: simplified by the rewrites that hold whatever the data
    (neurosym_cli/synth/simplify.py ``simplify_static``; the result file keeps the program as it was evaluated),
    its header's degree term in the page's words. Returns (text, Program, the lines the page says under it)."""
    from neurosym_cli.degrees import objective_term
    from neurosym_cli.dsl import to_text
    from neurosym_cli.dsl.ast import Program
    from neurosym_cli.synth.simplify import simplify_static

    lines = text.splitlines()
    head = [ln.replace(" x degree ", f" x {objective_term(objective)} ") for ln in lines if ln.startswith("#")]
    program = parse("\n".join(ln for ln in lines if not ln.startswith("#")))
    rounds, notes = [], []
    for r, rules in enumerate(program.rounds, start=1):
        simple, changed = simplify_static(rules, vocab(task, features))
        rounds.append(simple)
        notes += [f"round {r}, {n}" if program.n_rounds > 1 else n for n in changed]
    program = Program(tuple(rounds))
    said = ([f"Shown simplified (whatever the data; rules numbered as evaluated: {'; '.join(notes)}); the result file keeps the program as "
             "evaluated."] if notes else [])
    return "\n".join(head + [to_text(program).rstrip()]), program, said


def readings(program, task: str, features: str) -> list[str]:
    """A program's rules as the page lists them under it: '- [round r, ]rule k: <reading>'."""
    from neurosym_cli.dsl import describe

    out = []
    for r, rules in enumerate(program.rounds, start=1):
        head = f"round {r}, " if program.n_rounds > 1 else ""
        out += [f"- {head}rule {k}: {describe(rule, vocab(task, features))}" for k, rule in enumerate(rules, start=1)]
    return out
