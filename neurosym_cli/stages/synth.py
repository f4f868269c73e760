"""Synthesize into the run directory (`neurosym synth`): the oracle dataset D (collected once per oracle and
reused), then one MCMC search per communication round (paper sections 3.2-3.4, appendix A), or, for dt, one
decision tree per round (appendix B). Writes program.txt (or tree.json), summary.json and trace.csv."""

from __future__ import annotations

from pathlib import Path
import torch

from .. import __version__
from ..config import ConfigError, RunConfig, UserError
from ..degrees import objective_form
from ..dsl.ast import Program
from ..dsl.printer import to_text
from ..dsl.sampling import MOVE_HELP
from ..run import RunDir, show_command, synth_command, train_command
from ..run.checkpoints import open_checkpoint, policy_from_payload
from ..run.summary import is_program_summary
from ..run.layout import PROGRAM, TREE
from ..tasks import make_task
from ..synth.dataset import DataBucket, load_or_collect, subsample
from ..synth.objective import CachedScorer
from ..synth.search import RoundSpec, as_program, search_round
from ..synth.simplify import rule_stats, simplify
from ..utils.console import SearchDisplay, log, say, use_rich
from ..utils.cpu import runtime
from ..utils.device import resolve_device
from ..utils.lock import run_lock
from ..utils.tracking import Tracker
from ..dsl.files import save_program
from ..utils.io import read_json, write_csv, write_json
from ..utils.seeding import STREAM_SYNTH, STREAM_SYNTH_DATA, generator, seed_everything
from . import RunInfo
from .front import round_front, write_front
from .show import render
from .tracked import open_run


SEARCH_SCALARS = ("objective", "current", "best", "best_l1", "best_degree", "accepted")
"""the columns of trace.csv sent to the run tracker at every proposal"""


def synthesize(cfg: RunConfig, info: RunInfo) -> dict:
    """Search the program (or fit the tree) of ``cfg``, unless the run directory has it already (overwrite=true
    searches again). Outside sweeps, a new program is shown with its readings."""
    artifact = cfg.baseline.artifact(cfg)
    if artifact is None:
        raise ConfigError(f"synth makes programs (baseline=prog, det-prog) or trees (baseline=dt), "
                          f"not {cfg.baseline.name}")
    if cfg.program:
        raise ConfigError("synth writes its program into the run directory; program= is for eval, retrain and "
                          "show-program")
    rd = RunDir(cfg)
    result = rd.artifact_file()
    if not cfg.overwrite and front_stale(cfg):
        log.warning("the front %s holds random rules or is unreadable, though %s searches argmax rules only (a "
                    "front searched before 2026-12-05): searching again", rd.front_file, cfg.baseline.name)
    if not cfg.overwrite and searched(cfg):
        from ..run.models import scheme_provider

        scheme_provider(cfg)  # a corrupt result is an error, never "already done"
        log.info("already synthesized: %s (overwrite=true searches again)", result)
        return {"program": str(result), **_terms(rd.summary_file)}
    with run_lock(rd.synth_dir), open_run(cfg, stage="synth", run=f"synth-{rd.program_tag}") as tracker:
        policy, env, data, device = collect_dataset(cfg)
        out = SYNTHESIZERS[artifact.file](cfg, info, policy, env, data, device, tracker=tracker)
        tracker.summary({f"synth/{k}": v for k, v in out.items() if k in ("objective", "l1", "degree")})
        for f in (result, rd.summary_file, rd.trace_file, rd.front_file):
            tracker.artifact(f)
        return out


def front_stale(cfg: RunConfig) -> bool:
    """Whether ``cfg``'s search (det-prog's) has a front that must be searched again: one holding programs outside
    its space (synth/front.leaves_space: random rules), or unreadable."""
    from ..synth.front import leaves_space

    path = RunDir(cfg).front_file
    if not (getattr(cfg.baseline, "det", False) and cfg.synth.front and path.exists()):
        return False  # only det-prog's space excludes what a front may hold (a tree's scheme has no det)
    try:
        return leaves_space(read_json(path), True)
    except (UserError, KeyError, TypeError, AttributeError, ValueError):  # ValueError: a program that does not parse
        return True  # of another shape: searched again like a missing one


def searched(cfg: RunConfig) -> bool:
    """Whether the run directory holds ``cfg``'s search, reused unless overwrite=true: its result and summary and,
    for a program under synth.front=true, a front that fits its search."""
    artifact = cfg.baseline.artifact(cfg)
    rd = RunDir(cfg)
    if artifact is None or not (rd.artifact_file().exists() and rd.summary_file.exists()):
        return False
    return not (cfg.synth.front and artifact.file == PROGRAM) or (rd.front_file.exists() and not front_stale(cfg))


def read_summary(cfg: RunConfig) -> dict:
    """summary.json of ``cfg``'s program search, of the shape ``search_program`` writes; else one line naming the
    command that searches it again."""
    return read_json(RunDir(cfg).summary_file, f"{synth_command(cfg)} overwrite=true",
                     is_program_summary)


def _terms(summary: Path) -> dict:
    """The objective terms a finished search recorded (summed over rounds), or nothing when unreadable."""
    try:
        rounds = read_json(summary)["rounds"]
        return {k: sum(float(x[k]) for x in rounds) for k in ("objective", "l1", "degree")}
    except (UserError, KeyError, TypeError, ValueError):
        return {}  # a tree's summary, or one of another shape: the program itself was checked above


def collect_dataset(cfg: RunConfig):
    """(oracle policy, env, the dataset D, device) of ``cfg``: D is collected once per oracle and then reused."""
    device = resolve_device(cfg.device)
    seed_everything(cfg.seed)
    policy = policy_from_payload(open_checkpoint(cfg, oracle=True)).to(device).eval()
    env = make_task(cfg.task, cfg.horizon)
    data = load_or_collect(RunDir(cfg).dataset_file, synth_command(cfg), env, policy,
                           rollouts=cfg.budget.synth_rollouts, stride=cfg.synth.stride,
                           gen=generator(cfg.seed, STREAM_SYNTH_DATA), device=device,
                           oracle_by=train_command(cfg, oracle=True))
    return policy, env, data, device


def search_program(cfg: RunConfig, info: RunInfo, policy, env, data: list[DataBucket], device: torch.device, *,
                   tracker: Tracker) -> dict:
    """MCMC per round (appendix A), every proposal's scalars to ``tracker`` (search/<name>, or
    search/round<r>/<name> with several rounds); writes program.txt, summary.json, trace.csv (and front.json)."""
    spec = RoundSpec(steps=cfg.budget.mcmc_steps, restarts=cfg.synth.restarts, final_fraction=cfg.synth.final_fraction,
                     temperature=cfg.synth.temperature, rules=cfg.rules, max_depth=cfg.synth.max_depth,
                     det=cfg.baseline.det, own_scores=cfg.synth.own_scores, patience=cfg.synth.patience,
                     search=cfg.synth.search)
    results, trace, rounds, fronts = [], [], [], []
    rich = use_rich(cfg.progress, info.multirun)
    rd = RunDir(cfg)
    tag = rd.program_tag
    for r in range(cfg.task.rounds):
        # appendix A: each round's program is searched alone, the other rounds keep soft attention
        def make_scorer(objective: str, r: int = r) -> CachedScorer:
            return CachedScorer(policy, env, data, round_idx=r, version=cfg.features, lam=cfg.lam,
                                objective=objective, cap=cfg.rules, samples=cfg.synth.random_samples,
                                gen=generator(cfg.seed, STREAM_SYNTH, r), device=device, backend=cfg.synth.backend)

        scorer = make_scorer(cfg.synth.objective)
        coarse = None
        if cfg.synth.coarse > 1:  # the restarts' scorer: every coarse-th state of D, its own random numbers
            coarse = CachedScorer(policy, env, subsample(data, cfg.synth.coarse), round_idx=r, version=cfg.features,
                                  lam=cfg.lam, objective=cfg.synth.objective, cap=cfg.rules,
                                  samples=cfg.synth.random_samples, gen=generator(cfg.seed, STREAM_SYNTH, 300 + r),
                                  device=device, backend=cfg.synth.backend, scale=scorer.scale)
        label = f"synth {cfg.task.name} {tag}" + (f" round {r + 1}" if cfg.task.rounds > 1 else "")
        group = "search/" + (f"round{r + 1}/" if cfg.task.rounds > 1 else "")
        with SearchDisplay(label, spec.steps, cfg.lam, rich, MOVE_HELP, cfg.synth.objective) as disp:
            def on_step(step: int, result, row: dict, group: str = group) -> None:
                disp.update(step, result, row)
                tracker.log(step, {group + k: row[k] for k in SEARCH_SCALARS})

            res = search_round(scorer, spec, f"{cfg.seed}/{r}/{tag}", generator(cfg.seed, STREAM_SYNTH, 100 + r),
                               on_step, coarse)
        disp.summary(res)
        searched, searched_rules = to_text(as_program([res])), res.best
        dropped: list[str] = []
        if cfg.synth.simplify:
            simple, dropped = simplify(scorer, res.best)
            if simple != res.best:  # the same objective (or better) with less text: what a reader gets
                res.best, res.best_score = simple, scorer.score(simple)
            for line in dropped:
                log.info("simplify: %s", line)
        stats = rule_stats(scorer, res.best)
        full = scorer.full_score(as_program([res])) if cfg.task.rounds == 1 else None
        results.append(res)
        trace += [{"round": r + 1, **row} for row in res.trace]
        rounds.append({"round": r + 1, "objective": res.best_score.total, "l1": res.best_score.l1,
                       "degree": res.best_score.degree, "seconds": res.seconds,
                       "proposals_per_second": res.proposals_per_second, "acceptance": res.acceptance(),
                       "proposed": dict(res.proposed), "rows_recomputed": scorer.rows_recomputed,
                       "backend": "numba" if scorer.compiled else "torch",
                       "full_forward_check": None if full is None else full.total,
                       "simplified": dropped, "searched_program": searched, "rule_stats": stats,
                       "stopped_early": res.stopped, "hall_of_fame": hall_of_fame(res, searched_rules),
                       **({"scale": [scorer.scale.l1, scorer.scale.degree]} if scorer.scale else {})})
        if cfg.synth.front:  # after everything above: the front's chains move no number of the single-lam search
            fronts.append(round_front(cfg, spec, scorer, [rules for _, rules in res.hall.by_degree.values()],
                                      round_idx=r, tag=tag, make_scorer=make_scorer))
    program = as_program(results)
    header = [f"neurosym program for {cfg.task.name}: rules={cfg.rules} lam={cfg.lam:g} features={cfg.features}"
              f" det={str(cfg.baseline.det).lower()} seed={cfg.seed} budget={cfg.budget.name}"]
    form = objective_form(cfg.synth.objective)
    header += [f"round {x['round']}: objective {x['objective']:.4f} = "
               f"{form.formula(x['l1'], x['degree'], cfg.lam, x.get('scale', (1.0, 1.0)))}" for x in rounds]
    # one unit, the program last (run/summary.py): a Ctrl-C between the writes leaves a summary without a program
    # (synth searches again), never a program without its summary or beside another search's
    _drop(rd.program_file)
    _drop(rd.front_file)  # a front belongs to the search that made it
    write_csv(rd.trace_file, trace)
    write_json(rd.summary_file, {
        "command": "synth", "version": __version__, "task": cfg.task.name, "tag": tag,
        "rules": cfg.rules, "lam": cfg.lam, "features": cfg.features, "det": cfg.baseline.det,
        "objective": cfg.synth.objective, "steps": spec.steps, "dataset": str(rd.dataset_file),
        "dataset_states": sum(b.states for b in data), "rounds": rounds, "program": to_text(program),
        "runtime": runtime(), "config": cfg.record(),
    })
    save_program(rd.program_file, to_text(program), header)
    say(f"[green]synthesized[/] {rd.program_file}")
    if fronts:
        write_front(rd.front_file, cfg, tag, fronts)
        say(f"[green]degree-budget front[/] {rd.front_file} (`{show_command(cfg)}` prints it)")
    if not info.multirun:
        render(program, env.features(cfg.features).vocab, rounds, cfg.lam, objective=cfg.synth.objective)
    return {"program": str(rd.program_file), "objective": sum(x["objective"] for x in rounds),
            "l1": sum(x["l1"] for x in rounds), "degree": sum(x["degree"] for x in rounds)}


def _drop(result: Path) -> None:
    """Remove the result an overwrite replaces before its new summary is written: a Ctrl-C before the new result
    is in place must not leave the old one beside the new search's summary."""
    try:
        result.unlink()
    except FileNotFoundError:
        pass
    except OSError as e:
        raise UserError(f"cannot replace {result}: {e.strerror or e}") from None


def hall_of_fame(res, picked: tuple) -> dict[str, list[dict]]:
    """summary.json's hall of fame of one round: the non-dominated best programs by complexity and by degree
    level (``mcmc.HallOfFame.front``), the search's pick (before simplification) marked."""
    def row(level: int, s, rules) -> dict:
        return {"level": level, "objective": s.total, "l1": s.l1, "degree": s.degree,
                "program": to_text(Program((rules,))), "chosen": rules == picked}

    return {by: [row(*x) for x in res.hall.front(by)] for by in ("complexity", "degree")}


def fit_trees(cfg: RunConfig, info: RunInfo, policy, env, data: list[DataBucket], device: torch.device, *,
              tracker: Tracker) -> dict:
    """dt (appendix B): per round, label every pair of D by the greedy global hard attention with in- and
    out-degree <= K from the oracle's soft attention, then fit a tree on the pair features."""
    from ..synth.tree import fit_tree, greedy_hard_attention, soft_attention

    policy = policy.cpu()
    fmap = make_task(cfg.task, cfg.horizon).features(cfg.features)
    trees, rounds = [], []
    for r in range(cfg.task.rounds):
        xs, ys = [], []
        for b in data:
            labels = greedy_hard_attention(soft_attention(policy, b, r), cfg.rules)  # (S, N, N)
            feats = fmap.view(b.agent, b.rel)
            off = ~torch.eye(b.n_agents, dtype=torch.bool).expand(b.states, -1, -1)
            xs.append(torch.stack([feats[f].expand(b.states, b.n_agents, b.n_agents)[off] for f in feats.names], -1))
            ys.append(labels[off])
            names = feats.names
        x, y = torch.cat(xs), torch.cat(ys)
        g = generator(cfg.seed, STREAM_SYNTH, 200 + r)
        keep = torch.randperm(len(y), generator=g)[:300_000]  # bound the fitting time
        tree, fit_info = fit_tree(x[keep], y[keep], names, (3, 5, 10, 20), cfg.seed)
        trees.append(tree)
        rounds.append({"round": r + 1, "pairs": int(len(keep)), "positive_fraction": float(y[keep].float().mean()),
                       **fit_info, "nodes": len(tree.left)})
        log.info("dt round %d: depth %d, validation accuracy %.3f, %d nodes", r + 1, fit_info["depth"],
                 fit_info["validation_accuracy"][fit_info["depth"]], len(tree.left))
    rd = RunDir(cfg)
    tree_file = rd.artifact_file()
    _drop(tree_file)  # the summary first and the tree last, as a program's (search_program)
    write_json(rd.summary_file, {"command": "synth", "version": __version__, "task": cfg.task.name,
                                 "tag": rd.program_tag, "rules": cfg.rules, "rounds": rounds,
                                 "runtime": runtime(), "config": cfg.record()})
    write_json(tree_file, {"rounds": [t.to_dict() for t in trees]})
    say(f"[green]fitted[/] {tree_file}")
    return {"tree": str(tree_file)}


SYNTHESIZERS = {PROGRAM: search_program, TREE: fit_trees}
"""what `synth` runs to make each kind of artifact a scheme names (``Artifact.file``, schemes/searched.py)"""
