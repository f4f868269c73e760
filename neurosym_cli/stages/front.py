"""`neurosym synth synth.front=true`: the degree-budget front of each round beside the single-lam program
(synth/front.py searches it), written to synth/<tag>/front.json (the record) and front.csv (one row per round and
budget); `neurosym show-program` prints it."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..config import RunConfig
from ..utils.io import read_json, write_csv, write_json

if TYPE_CHECKING:  # show-program reads a front without torch: the search is imported where it runs
    from ..synth.objective import CachedScorer
    from ..synth.search import RoundSpec

FRONT_STREAM = 400
"""the generator stream of round r's front is (STREAM_SYNTH, FRONT_STREAM + r): none the single-lam search reads"""


def round_front(cfg: RunConfig, spec: RoundSpec, scorer: CachedScorer, archive: list[tuple], *, round_idx: int,
                tag: str, make_scorer) -> dict:
    """One round's front: {round, l1_silent, steps, budgets: [rows of synth.front.search_front], range: [its
    nearest-within-r rows]}. ``make_scorer``
    (objective -> CachedScorer on the same D and random numbers) builds a max in+out scorer when the search's own
    counts the hinge."""
    from ..synth.front import default_budgets, search_front
    from ..utils.seeding import STREAM_SYNTH, generator

    front_scorer = make_scorer("paper") if scorer.form.hinge else scorer
    n_max = max(d.n for d in scorer.data)
    budgets = sorted(set(cfg.synth.front_budgets)) or default_budgets(cfg.rules, n_max)
    steps = cfg.synth.front_steps or max(1, spec.steps // max(1, len(budgets) - 1))
    rows, near = search_front(front_scorer, spec, archive=archive, budgets=budgets, steps=steps,
                        seed=f"{cfg.seed}/{round_idx}/{tag}/front",
                        gen=generator(cfg.seed, STREAM_SYNTH, FRONT_STREAM + round_idx))
    return {"round": round_idx + 1, "l1_silent": front_scorer.silent_l1(), "steps_per_budget": steps, "budgets": rows,
            "range": near}


def write_front(path: Path, cfg: RunConfig, tag: str, rounds: list[dict]) -> None:
    """front.json (the record: every round's rows with the search's settings) and front.csv beside it."""
    write_json(path, {"command": "synth", "kind": "front", "task": cfg.task.name, "tag": tag, "rules": cfg.rules,
                      "features": cfg.features, "det": cfg.baseline.det, "lam": cfg.lam,
                      "objective": cfg.synth.objective, "rounds": rounds, "config": cfg.record()})
    write_csv(path.with_suffix(".csv"), [{"round": r["round"], "kind": kind, "radius": row.get("radius", ""), **row}
                                         for r in rounds for kind, key in (("budget", "budgets"), ("near", "range"))
                                         for row in r.get(key, [])])


def is_front(rec: object) -> bool:
    """Whether a record is a front.json of this shape: rounds of rows with budget, L1, degrees and program."""
    rounds = rec.get("rounds") if isinstance(rec, dict) else None

    def rows(r: dict, key: str) -> bool:  # "range" (the sparse end's near rows) is absent in fronts before it
        return isinstance(r.get(key, []), list) and all(
            isinstance(b, dict) and isinstance(b.get("program"), str) and all(
                isinstance(b.get(k), (int, float)) and not isinstance(b.get(k), bool)
                for k in ("budget", "l1", "l1_ratio", "degree", "max_in", "max_out")) for b in r.get(key, []))

    return isinstance(rounds, list) and bool(rounds) and all(
        isinstance(r, dict) and isinstance(r.get("budgets"), list) and rows(r, "budgets") and rows(r, "range")
        for r in rounds)


def read_front(path: Path, remake: str) -> dict:
    """front.json, checked for the shape ``write_front`` writes; else one line naming ``remake``."""
    return read_json(path, remake, is_front)


def print_front(front: dict, source: str) -> None:
    """The front of every round as a table: budget, L1 (and its share of silence's), the degrees on D, the
    program; a row whose program is the previous row's is marked as such (the front is monotone); then the sparse
    end's nearest-within-r rows."""
    from rich.table import Table

    from ..utils.console import console

    for r in front["rounds"]:
        name = f"degree-budget front: {source}" + (f", round {r['round']}" if len(front["rounds"]) > 1 else "")
        t = Table(title=name, header_style="bold",
                  caption="per budget of max in+out on D, the lowest L1 found within it (L1 / silence: its share of "
                          "the action gap that hearing nobody leaves); 'near' rows: the nearest agent within the "
                          "largest radius in budget, candidates too; pick a row and run it with program=FILE "
                          "(docs/extending.md, 'The trade-off')")
        for c in ("budget", "L1", "L1 / silence", "max in+out", "max in", "max out", "program"):
            t.add_column(c, justify="left" if c == "program" else "right")
        previous = None
        for b in r["budgets"]:
            text = "[dim]as above[/]" if b["program"] == previous else b["program"]
            t.add_row(f"{b['budget']:g}", f"{b['l1']:.4f}", f"{b['l1_ratio']:.3f}", f"{b['degree']:.3f}",
                      f"{b['max_in']:.3f}", f"{b['max_out']:.3f}", text)
            previous = b["program"]
        for b in r.get("range", []):  # the sparse end's nearest-within-r candidates (synth/front.range_rows)
            t.add_row(f"{b['budget']:g} near", f"{b['l1']:.4f}", f"{b['l1_ratio']:.3f}", f"{b['degree']:.3f}",
                      f"{b['max_in']:.3f}", f"{b['max_out']:.3f}", b["program"])
        console.print(t)
