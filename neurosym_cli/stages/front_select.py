"""`neurosym pipeline pipeline.select=front`: the run's program chosen among its search's degree-budget front by
what the user cares about, the task's loss on validation seeds after retraining (the paper's appendix B, over the
front's budgets instead of a lambda grid; issue 37).

    1. the oracle, its search with the front (synth.front=true: one program per budget of max in+out on D) and
       no-comm's own model;
    2. every distinct program of the front (the lowest budget that reaches it), and at the sparse end the
       nearest-within-r programs (synth/front.range_rows), is written to select/front/<tag>-<name>.txt (name
       b<budget>, near<budget>) and run as program= (its label and retrained model are named by its
       content); the oracle is retrained under it (budget.retrain_rollouts, the retraining prog-retrained gets
       anyway, so the pick's is reused) and validated: loss per validation seed (``budget.val_seeds``, episodes of
       their own stream, never a test episode; select.validate) and max in+out;
    3. tf-full and no-comm validated the same way: communication helps when the paired 95 % Student-t interval of
       no-comm - tf-full over the validation seeds lies above 0; then silent programs are no candidates;
    4. the pick by select.choose: among the candidates whose paired 95 % interval of the loss difference to the
       validation-best ends below pipeline.margin x the best's mean loss (an equivalence test), the lowest
       validation max in+out (the lower mean loss on a tie);
    5. the choice and every candidate's rows in select/front/<tag>.json; the pipeline then makes and evaluates prog
       and prog-retrained under the picked program, on the test seeds.

det-prog (argmax rules only, appendix C's ablation of the method) goes through the same steps with its own front
when det-prog or det-prog-retrained is listed (``Family``; its files det-<tag>...), after prog's: in step 4 its
best is prog's validation-best where that is lower (``Family.matches``, ``reference``), so the ablation is read at
the method's loss.
"""

from __future__ import annotations

import dataclasses
import hashlib
import time
from pathlib import Path
from typing import Any, Callable, Sequence

from .. import __version__
from ..baselines import ORACLE, run_args
from ..config import RunConfig, UserError
from ..dsl.ast import Program
from ..dsl.files import save_program
from ..dsl.parser import parse
from ..dsl.printer import to_text
from ..run import RunDir
from ..schemes import get
from ..stats import mean_ci
from ..utils.console import clock, log, say
from ..utils.io import read_json, write_json
from .flow import Flow, Job
from .front import read_front
from .guard import SILENT, communication_helps
from .validation import choose, validate

SILENT_BASELINE = "no-comm"
"""the model that hears nobody (the rule's reference)"""


@dataclasses.dataclass(frozen=True)
class Family:
    """A searched program and the baselines that run under it: the oracle as it is (``search``, whose synth writes
    the front) and the oracle retrained under it (``retrained``: what each candidate is retrained and validated
    as)."""

    search: str
    retrained: str
    matches: "Family | None" = None
    """the family whose best validation loss this one's pick must match where its own best is worse: an ablation is
    compared at the method's loss (appendix C: "a similar loss but worse out-degrees"), not at a loss of its own"""

    @property
    def runs(self) -> tuple[str, str]:
        return self.search, self.retrained

    @property
    def node(self) -> str:
        """the key of its front selection in the pipeline's graph"""
        return f"front selection {self.search}"

    @property
    def retrained_node(self) -> str:
        """the key of its front's retrainings and validations in the pipeline's graph (before the pick)"""
        return f"front retraining {self.search}"


PROG = Family("prog", "prog-retrained")
"""the method (sections 3.3-3.5); program= is its family's alone"""
DET = Family("det-prog", "det-prog-retrained", matches=PROG)
"""appendix C's ablation, the method without random rules: under pipeline.select=front it gets its own front and
pick by the same rule, at the method's loss (``matches``), as under the paper's method it gets select's own pick"""
FAMILIES = (PROG, DET)


def family_of(name: str) -> Family | None:
    """The family baseline ``name`` runs in (None: it runs under no searched program)."""
    return next((f for f in FAMILIES if name in f.runs), None)


def fronted(cfg: RunConfig) -> list[Family]:
    """The families whose program the pipeline picks among their search's front: under pipeline.select=front, each
    with a baseline in ``cfg.baselines``; prog's not when program= gives it its program."""
    if cfg.pipeline.select != "front":
        return []
    return [f for f in FAMILIES if any(b in f.runs for b in cfg.baselines) and not (f is PROG and cfg.program)]


RULE = ("retrained under each distinct program of the front, validated on budget.val_seeds: among the programs "
        "whose paired 95% Student-t interval of the validation loss difference to the best ends below "
        "pipeline.margin x the best's mean loss, the lowest validation max in+out (lower mean loss on a tie); "
        "silent programs are no candidates when tf-full beats no-comm on validation (paired 95% interval of "
        "no-comm - tf-full above 0)")
"""the rule, as the choice file states it"""
MATCHED = ("; the best is {family}'s validation-best candidate where its loss is lower (the ablation at the method's "
           "loss); when no program is similar to it, the lowest mean loss")
"""what the rule adds for a family that ``matches`` another"""

# --------------------------------------------------------------------------------------------- the rule
def pick(rows: Sequence[dict[str, Any]], *, helps: bool, margin: float | None = None,
         reference: Sequence[float] | None = None) -> list[dict[str, Any]]:
    """The rule on validation rows (``name``, ``loss`` per validation seed, ``degree``: mean max in+out over them).

    Silent rows (degree below guard.SILENT) are left out when ``helps`` (unless every row is silent: then they stay,
    and the guard's line follows). ``margin``: select.choose's equivalence margin (None: the paper's test);
    ``reference``: the loss per validation seed to match where it is lower than the rows' best (``reference``).
    Returns select.choose's annotated rows of the candidates (one ``picked``), then the left-out rows with
    ``excluded`` true."""
    silent = [r for r in rows if r["degree"] < SILENT]
    keep = [r for r in rows if not (helps and r["degree"] < SILENT)] or list(rows)
    chosen = choose(keep, margin=margin, reference=reference)
    for r in chosen:
        r["excluded"] = False
    left = [dict(r, excluded=True, similar=None, picked=False) for r in silent if not any(r is k for k in keep)]
    for r in left:
        r["loss_mean"], r["loss_ci"] = mean_ci(r["loss"])
    return chosen + left


# --------------------------------------------------------------------------------------------- candidates
def candidates(front: dict) -> list[dict[str, Any]]:
    """The distinct programs of a front.json, lowest budget first: {name, budget, program (every round's rules,
    text), l1 and degree (per round, on D)}; then the sparse end's nearest-within-r programs (synth/front.range_rows;
    name near<budget>) of the budgets every round has one for. A program (all rounds) already listed is no new
    candidate."""
    rounds = sorted(front["rounds"], key=lambda r: r["round"])
    budgets = [b["budget"] for b in rounds[0]["budgets"]]
    if any([b["budget"] for b in r["budgets"]] != budgets for r in rounds):
        raise UserError("the front's rounds list different budgets; search it again with overwrite=true")
    lists = [("b", budgets, [{row["budget"]: row for row in r["budgets"]} for r in rounds])]
    near = [{row["budget"]: row for row in r.get("range", [])} for r in rounds]  # absent in fronts before them
    lists.append(("near", [b for b in near[0] if all(b in n for n in near)], near))
    out, seen = [], set()
    for prefix, keys, by_round in lists:
        for budget in keys:
            rows = [r[budget] for r in by_round]
            program = Program(tuple(parse(row["program"]).rounds[0] for row in rows))
            text = to_text(program)
            if text in seen:
                continue
            seen.add(text)
            out.append({"name": f"{prefix}{float(budget):g}", "budget": float(budget), "program": text,
                        "l1": [row["l1"] for row in rows], "degree_on_d": [row["degree"] for row in rows]})
    return out


def about(cand: dict) -> str:
    """A candidate in words: 'budget 2', or 'budget 2, the nearest agent within a radius'."""
    near = str(cand.get("name", "")).startswith("near")
    return f"budget {cand['budget']:g}" + (", the nearest agent within a radius" if near else "")


def write_candidate(path: Path, cand: dict, tag: str) -> None:
    """A candidate's program file; left as it is when it already holds the same bytes (its name and content name
    its label and retrained model: rewriting the same text keeps them)."""
    header = [f"{about(cand)} of the degree-budget front of {tag}: L1 on D "
              + ", ".join(f"{x:.6g}" for x in cand["l1"]) + ", max in+out on D "
              + ", ".join(f"{x:.4g}" for x in cand["degree_on_d"])]
    text = "".join(f"# {h}\n" for h in header) + cand["program"]
    if path.exists() and path.read_text() == text:
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    save_program(path, cand["program"], header)


# --------------------------------------------------------------------------------------------- after the stage
ONE_BASELINE, SEVERAL = ("eval", "render", "export"), ("stress", "figures")
"""the verbs that, given no program=, run a family's baselines under the pipeline's front pick when there is one
(what the pipeline evaluated is what they show): of one baseline= (of a family), or of several (``program_for``)"""


def front_program(cfg: RunConfig, fam: Family) -> Path | None:
    """The file of the pipeline's pick among ``fam``'s front (select/front/<tag>.json) for ``cfg``'s task, budget,
    seed and search settings; None where pipeline.select is not front or no pipeline chose."""
    if cfg.pipeline.select != "front":
        return None
    rd = RunDir(dataclasses.replace(cfg, baseline=get(fam.search), program=""))
    tag = rd.program_tag
    choice = rd.front_choice_file(tag)
    if not choice.exists():
        return None  # no pipeline ran this search's selection: the single-lam program, as before
    rec = read_json(choice, f"neurosym pipeline {run_args(cfg)}", {"picked": dict})
    try:
        path = rd.front_candidate_file(tag, rec["picked"].get("name") or f"b{float(rec['picked']['budget']):g}")
        # ^ here, wherever the runs root moved (a choice before near candidates names none: a budget's)
    except (KeyError, TypeError, ValueError):
        raise UserError(f"corrupt front choice {choice}; delete it and run `neurosym pipeline {run_args(cfg)}`") \
            from None
    if not path.exists():
        raise UserError(f"the front choice {choice} names {path}, which is gone; run `neurosym pipeline "
                        f"{run_args(cfg)}` to write it again")
    made_on = rec.get("front_sha1")  # the front it chose among (recorded since the choice file exists)
    if made_on and rd.front_file.exists() and hashlib.sha1(rd.front_file.read_bytes()).hexdigest() != made_on:
        raise UserError(f"the front choice {choice} was made among another front than {rd.front_file} (searched "
                        f"again since); run `neurosym pipeline {run_args(cfg)}` to choose among it again")
    return path


def apply_front_pick(cfg: RunConfig, verb: str) -> RunConfig:
    """``cfg`` with program= the pipeline's pick among its family's front, when ``verb`` follows the pick for
    ``cfg``'s baseline (of several: prog's, the others by ``program_for``), no program= is given and the pipeline
    chose under pipeline.select=front; else ``cfg``."""
    fam = PROG if verb in SEVERAL else family_of(cfg.baseline.name) if verb in ONE_BASELINE else None
    if fam is None or cfg.program:
        return cfg
    path = front_program(cfg, fam)
    if path is None:
        return cfg
    say(f"{cfg.baseline.name if verb in ONE_BASELINE else ', '.join(fam.runs)}: the pipeline's pick among the "
        f"front ({path.name}); program=<file> for another, pipeline.select=none for the single-lam search's program")
    return dataclasses.replace(cfg, program=str(path))


def program_for(cfg: RunConfig, name: str) -> str:
    """The program file baseline ``name`` runs under in a verb of several baselines (stress, figures): program= (given,
    or prog's pick by apply_front_pick) for prog's family, the pipeline's pick for another family's (its own search's
    program where none), "" for a baseline of none."""
    fam = family_of(name)
    if fam is None:
        return ""
    if fam is PROG:
        return cfg.program
    path = front_program(cfg, fam)
    return str(path) if path else ""


def reference(cfg: RunConfig, fam: Family) -> dict[str, Any] | None:
    """The validation-best candidate of the family ``fam`` matches (``Family.matches``), from the choice file the
    same pipeline just wrote for it, as {family, choice, name, loss (per validation seed), loss_mean, degree}; None
    (said in one line) when that choice is absent, was made on another front or on another number of validation
    seeds, or holds no candidate."""
    other = fam.matches
    if other is None:
        return None
    rd = RunDir(dataclasses.replace(cfg, baseline=get(other.search), program=""))
    choice = rd.front_choice_file(rd.program_tag)
    rec = read_json(choice, f"neurosym pipeline {run_args(cfg)}", {"candidates": list}) if choice.exists() else {}
    sha = hashlib.sha1(rd.front_file.read_bytes()).hexdigest() if rd.front_file.exists() else None
    rows = [r for r in rec.get("candidates", []) if not r.get("excluded")]
    why = ("no choice" if not rec else "another front" if rec.get("front_sha1") != sha
           else "other validation seeds" if rec.get("val_seeds") != cfg.budget.val_seeds else "" if rows
           else "no candidate")
    if why:
        say(f"{fam.search}: read at its own validation-best, not at {other.search}'s ({choice}: {why})")
        return None
    best = min(rows, key=lambda r: r["loss_mean"])
    return {"family": other.search, "choice": str(choice), "name": best["name"], "loss": best["loss"],
            "loss_mean": best["loss_mean"], "degree": best["degree"]}


# --------------------------------------------------------------------------------------------- the stage
def validation(cfg: RunConfig, baseline: str, program: str = "") -> dict[str, Any]:
    """``baseline``'s validation rows (stages/validation.py), under ``program`` (a file; "" for none)."""
    return validate(dataclasses.replace(cfg, baseline=get(baseline), cmd="eval", program=program))


@dataclasses.dataclass
class Validated:
    """A family's front, retrained and validated (steps 2-3): its candidates' validation ``rows``, tf-full's and
    no-comm's rows, whether communication helps (and no-comm - tf-full, its 95 % half-width), the search's run
    directory and tag, and when the work started (time.perf_counter)."""

    rows: list[dict[str, Any]]
    tf: dict[str, Any]
    nc: dict[str, Any]
    helps: bool
    gap: tuple[float, float]
    rd: RunDir
    tag: str
    t0: float


def validated_front(cfg: RunConfig, fam: Family, retrain: Callable[[str, str], Job],
                    validate_job: Callable[[str, str], Job],
                    on_candidates: Callable[[list[str]], None] | None = None) -> Flow:
    """Steps 2-3 of the module docstring for ``fam``'s front, as a flow (stages/flow.py) that starts once step 1's
    artifacts are made; its value is a ``Validated``. ``retrain(baseline, program)``: the job that retrains
    ``baseline`` under a program file (the pipeline's stage); ``validate_job(baseline, program)``: the job of
    ``validation``; ``on_candidates``: told the program files about to be retrained (the pipeline's time left)."""
    t0 = time.perf_counter()
    search = dataclasses.replace(cfg, baseline=get(fam.search), program="")
    rd = RunDir(search)
    tag = rd.program_tag
    remake = f"neurosym synth {run_args(cfg)} synth.front=true overwrite=true"
    front = read_front(rd.front_file, remake)
    if any("range" not in r for r in front["rounds"]):
        log.warning(f"the front {rd.front_file} was searched before its sparse end offered the nearest agent within a "
                    f"radius (issue 37): `{remake}` searches it again with them")
    cands = candidates(front)
    tf, nc = yield [validate_job(ORACLE, ""), validate_job(SILENT_BASELINE, "")]
    helps, gap, gap_ci = communication_helps(tf["loss"], nc["loss"])
    near = sum(c["name"].startswith("near") for c in cands)
    say(f"front selection {cfg.task.name} {fam.search} ({tag}): {len(cands) - near} distinct program(s) of "
        f"{len(front['rounds'][0]['budgets'])} budgets and {near} nearest-within-r, {cfg.budget.val_seeds} "
        f"validation seeds; tf-full {mean_ci(tf['loss'])[0]:.4g}, no-comm "
        f"{mean_ci(nc['loss'])[0]:.4g} (no-comm - tf-full {gap:+.3g} ± {gap_ci:.3g}: communication "
        + ("helps, silence is no candidate)" if helps else "does not clearly help, silence may be chosen)"))
    if helps:  # a program silent on D is silent in every episode: no candidate, and no retraining spent on it
        talking = [c for c in cands if max(c["degree_on_d"]) >= SILENT]
        if talking and len(talking) < len(cands):
            say(f"front: {len(cands) - len(talking)} program(s) silent on D left out (communication helps)")
            cands = talking
    paths = [rd.front_candidate_file(tag, c["name"]) for c in cands]
    for k, (cand, path) in enumerate(zip(cands, paths), start=1):
        write_candidate(path, cand, tag)
        say(f"front {k}/{len(cands)}: {about(cand)} (max in+out on D "
            + ", ".join(f"{x:.2f}" for x in cand["degree_on_d"]) + "): queued for retraining")
    if on_candidates is not None:
        on_candidates([str(p) for p in paths])
    yield [retrain(fam.retrained, str(p)) for p in paths]
    vals = yield [validate_job(fam.retrained, str(p)) for p in paths]
    rows = []
    for k, (cand, path, v) in enumerate(zip(cands, paths, vals), start=1):
        m, h = mean_ci(v["loss"])
        say(f"front {k}/{len(cands)}: {about(cand)}: validation loss {m:.4g} ± {h:.3g}, max in+out "
            f"{v['degree']:.2f}")
        rows.append({"name": cand["name"], "budget": cand["budget"], "program_file": str(path),
                     "label": v["label"], "program": cand["program"], "l1_on_d": cand["l1"],
                     "degree_on_d": cand["degree_on_d"], "loss": v["loss"], "degree": v["degree"],
                     "max_in": v["max_in"], "max_out": v["max_out"]})
    return Validated(rows, tf, nc, helps, (gap, gap_ci), rd, tag, t0)


def choose_front(cfg: RunConfig, fam: Family, front: Validated, matched: bool = False) -> Path:
    """Steps 4-5 of the module docstring: the pick among ``front`` by the rule, written to the choice file; its
    program file. ``matched``: the pipeline chose among ``fam.matches``'s front first, and ``fam`` is read at its
    validation-best (``reference``) where that is lower than ``fam``'s own."""
    rd, tag, rows = front.rd, front.tag, front.rows
    ref = reference(cfg, fam) if matched else None
    ranked = pick(rows, helps=front.helps, margin=cfg.pipeline.margin, reference=ref["loss"] if ref else None)
    chosen = next(r for r in ranked if r["picked"])
    used = ref is not None and ref["loss_mean"] < min(r["loss_mean"] for r in ranked if not r["excluded"])
    if ref is not None and used:
        say(f"front selection {fam.search}: read at {ref['family']}'s validation-best ({ref['name']}, "
            f"{ref['loss_mean']:.4g}): " + ("the lowest degree similar to it" if chosen["similar"]
                                            else "none of its programs is similar to it, its lowest loss"))
    if front.helps and chosen["degree"] < SILENT:
        log.warning("every program of the front is silent on validation, though tf-full beats no-comm: the front "
                    "found no communicating program worth its degree; try synth.search=hybrid or more "
                    "budget.mcmc_steps")
    write_json(rd.front_choice_file(tag), {
        "command": "pipeline", "kind": "front-selection", "version": __version__, "task": cfg.task.name,
        "search": fam.search, "seed": cfg.seed, "budget": cfg.budget.name, "tag": tag, "front": str(rd.front_file),
        "front_sha1": hashlib.sha1(rd.front_file.read_bytes()).hexdigest(), "val_seeds": cfg.budget.val_seeds,
        "retrain_rollouts": cfg.budget.retrain_rollouts, "margin": cfg.pipeline.margin,
        "rule": RULE + (MATCHED.format(family=fam.matches.search) if fam.matches else ""),
        "reference": ref, "reference_used": used,
        "tf_full": {"loss": front.tf["loss"], "degree": front.tf["degree"]}, "no_comm": {"loss": front.nc["loss"]},
        "communication_helps": front.helps, "no_comm_minus_tf_full": list(front.gap),
        "picked": {k: chosen[k] for k in ("name", "budget", "program_file", "label", "program", "degree",
                                           "loss_mean")},
        "candidates": ranked, "seconds": time.perf_counter() - front.t0, "config": cfg.record()})
    say(f"[green]front selection[/]: {fam.search}: {about(chosen)}, validation loss {chosen['loss_mean']:.4g}, max "
        f"in+out {chosen['degree']:.2f} -> {rd.front_choice_file(tag)} ({clock(time.perf_counter() - front.t0)}); "
        f"{fam.search} and {fam.retrained} run under it")
    return Path(chosen["program_file"])
