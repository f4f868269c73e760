"""A program on screen: each rule in the paper's notation beside its plain-language reading, with the objective
terms of its search when known. Reads text and the task's feature declarations only (no torch), so
`neurosym show-program` answers at once."""

from __future__ import annotations

from pathlib import Path

from rich.panel import Panel
from rich.table import Table

from ..config import ConfigError, RunConfig, UserError
from ..run import RunDir, synth_command
from ..run.layout import FRONT
from ..run.summary import read_matching, summary_beside
from ..degrees import objective_form, objective_legend, objective_term
from ..dsl.ast import Program, rule_features
from ..dsl.vocabulary import FeatureSet
from ..dsl.printer import describe, rule_text
from ..utils.console import console, log
from ..dsl.files import load_program
from .front import print_front, read_front


def _features(rule, vocab: FeatureSet) -> str:
    """The rule's features, the asking agent's own (my) and the other agent's (its), styled apart."""
    names = sorted(rule_features(rule))
    mine = [n for n in names if vocab.agent_level(n)]
    its = [n for n in names if not vocab.agent_level(n)]
    parts = ([f"[cyan]my[/] {', '.join(mine)}"] if mine else []) + ([f"[magenta]its[/] {', '.join(its)}"] if its else [])
    return "; ".join(parts) or "none"


def _stats(info, n_rules: int) -> list[dict] | None:
    """The rule statistics of a summary's round, when they are there and fit the program's rules."""
    stats = info.get("rule_stats") if isinstance(info, dict) else None
    ok = isinstance(stats, list) and len(stats) == n_rules and all(
        isinstance(x, dict) and all(_number(x.get(k)) for k in ("fires", "edge_share", "removal_delta"))
        and isinstance(x.get("flags"), list) for x in stats)
    return stats if ok else None


def _number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def render(program: Program, vocab: FeatureSet, rounds: list[dict] | None, lam: float | None,
           title: str = "program", objective: str = "paper") -> None:
    """Print each rule in the paper's notation beside its reading, and the objective terms when known
    (``objective``: the search's synth.objective, which names its degree term)."""
    term = objective_term(objective)
    for r, rules in enumerate(program.rounds):
        t = Table(show_header=True, header_style="bold", expand=False,
                  caption="[cyan]my[/]: the asking agent's own state, the same for every candidate (a guard, or a "
                          "score that ties); [magenta]its[/]: the other agent as the asking agent observes it")
        info = rounds[r] if rounds and r < len(rounds) else None
        stats = _stats(info, len(rules))
        t.add_column("#", justify="right")
        t.add_column("rule (paper notation)")
        t.add_column("features read")
        t.add_column("reading")
        if stats:
            t.add_column("fires", justify="right")
            t.add_column("edges", justify="right")
            t.add_column("Δ objective\nif removed", justify="right")
        for k, rule in enumerate(rules, start=1):
            row = [str(k), rule_text(rule), _features(rule, vocab), describe(rule, vocab)]
            if stats:
                st = stats[k - 1]
                flags = "".join(f"\n[yellow]{f}[/]" for f in st["flags"])
                row[3] += flags
                delta = st["removal_delta"]
                row += [f"{100 * st['fires']:.0f}%", f"{100 * st['edge_share']:.0f}%",
                        "-" if delta != delta else f"{delta:+.4f}"]
            t.add_row(*row)
        if stats:
            t.caption += ("\nfires: share of (state, agent) of the synthesis dataset where the rule picks somebody; "
                          "edges: its share of the program's edges; Δ objective: the objective without the rule "
                          "minus with it (positive: the rule helps)")
        sub = ""
        if isinstance(info, dict) and lam is not None:
            try:
                sub = (f"objective {info['objective']:.4f} = L1 action error {info['l1']:.4f} + {lam:g} x {term} "
                       f"{info['degree']:.3f}")
                if objective_form(objective).scaled:  # the terms in the dataset's units (summary's scale)
                    sub = (f"objective {info['objective']:.4f} = "
                           + objective_form(objective).formula(info["l1"], info["degree"], lam, tuple(info["scale"])))
            except (KeyError, TypeError, ValueError):
                sub = ""  # a summary of another shape: the rules are still worth showing
        name = f"{title}, round {r + 1}" if program.n_rounds > 1 else title
        console.print(Panel(t, title=name, subtitle=sub or None, expand=False))
        simplified = info.get("simplified") if isinstance(info, dict) else None
        for line in simplified if isinstance(simplified, list) else []:
            console.print(f"[dim]simplified after the search:[/] {line}")
        hall = info.get("hall_of_fame") if isinstance(info, dict) else None
        if isinstance(hall, dict):
            hall_of_fame(hall, lam, name, objective)
    if rounds:
        console.print(f"[dim]{objective_legend(objective)}[/]")


def hall_of_fame(hall: dict, lam: float | None, name: str, objective: str = "paper") -> None:
    """PySR-style hall of fame of one round: the best program found at each complexity and at each degree level,
    dominated rows left out, the search's pick marked (summary.json's ``hall_of_fame``)."""
    term = objective_term(objective)
    heads = {"complexity": ("complexity", "rules + tests; kept when its objective beats every simpler program's"),
             "degree": (f"{term} ≤", f"the objective's {term} rounded up; kept when its L1 beats every lower "
                                    "level's")}
    for by, (head, why) in heads.items():
        rows = hall.get(by)
        if not isinstance(rows, list) or not rows or not all(isinstance(r, dict) for r in rows):
            continue
        t = Table(title=f"hall of fame by {by}: {name}", caption=why, header_style="bold")
        for c in (head, "objective", "L1", term, "program", ""):
            t.add_column(c, justify="left" if c in ("program", "") else "right")
        for r in rows:
            try:
                t.add_row(str(r["level"]), f"{r['objective']:.4f}", f"{r['l1']:.4f}", f"{r['degree']:.3f}",
                          str(r["program"]).strip(), "[green]◀ search's pick[/]" if r.get("chosen") else "")
            except (KeyError, TypeError, ValueError):
                return  # a summary of another shape: the program above stands
        console.print(t)


def _objective(meta: dict, default: str) -> str:
    """The synth.objective a summary's search ran under (it names the degree term), or ``default`` when the
    summary does not say one neurosym knows."""
    config = meta.get("config")
    synth = config.get("synth") if isinstance(config, dict) else None
    objective = synth.get("objective") if isinstance(synth, dict) else None
    if not isinstance(objective, str):
        return default
    try:
        objective_term(objective)
    except UserError:
        return default
    return objective


def show_program(cfg: RunConfig) -> dict:
    """The program of ``cfg`` (or ``program=PATH``) with the objective terms from its summary.json, if readable."""
    if not cfg.program and not cfg.baseline.has_program:
        raise ConfigError(f"baseline {cfg.baseline.name} runs under no program; show-program reads those of "
                          "baseline=prog, det-prog and their retrainings, or program=PATH")
    path = RunDir(cfg).program_file
    program = load_program(path, None if cfg.program else synth_command(cfg))
    from ..tasks.programs import check_program, feature_map

    fmap = feature_map(cfg)
    check_program(program, cfg, str(path), fmap)  # the features of this task only, as eval would insist
    rounds, lam, objective = None, None, cfg.synth.objective
    meta, why = read_matching(path, program)
    if meta is not None:
        rounds, lam = meta["rounds"], meta.get("lam") if _number(meta.get("lam")) else None
        objective = _objective(meta, objective)
    elif not cfg.program or summary_beside(path).exists():  # a file of the user's own need not have one
        again = "" if cfg.program else f"; `{synth_command(cfg)} overwrite=true` searches it again"
        log.warning("%s %s: its rules are shown without their objective terms%s", path, why, again)
    render(program, fmap.vocab, rounds, lam, title=str(Path(path)), objective=objective)
    front = path.parent / FRONT  # synth.front=true wrote one beside the program
    if front.is_file():
        print_front(read_front(front, f"{synth_command(cfg)} synth.front=true overwrite=true"), str(front))
    return {"program": str(path)}
