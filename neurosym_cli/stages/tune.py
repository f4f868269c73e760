"""`neurosym tune`: select's choice by an Optuna study instead of a grid (the tune extra: optuna, cmaes).

A trial draws lam (on a grid of ``tune.lam_step``), K, the feature map and the retraining's starting rate
(optim.retrain_lr, log-uniform), then runs select's own two jobs (``select.search_job``: the program searched or
reused and validated as prog; ``select.retrain_job``: the oracle retrained under it and validated again). Its value
is the mean validation loss after retraining, what select decides by. Pruning: the retraining loop reports no
validation loss while it runs, so a trial reports one intermediate value, its program's validation loss before
retraining (step 0), and the pruner (MedianPruner) stops it there, unretrained, when that is worse than the median of
the finished trials': the same funnel as select's finalists.

The study lives in ``tune.storage`` (SQLite in <exp_dir>/select/tune/optuna.db by default) under a name keyed by
everything that sets its trials; a rerun resumes it up to ``tune.trials`` finished trials, and processes on many
machines that run the same command (a sweep over ``tune.worker``, a SLURM array) share it. Heartbeats mark the trials
of a killed process failed, and they are run again. Every process ends by writing the study's table (select's
columns, and the rate) and its loss-degree Pareto front into select/tune/<study>/.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib
import json
import time
import warnings
from collections import Counter
from typing import Any, Callable

from .. import __version__
from ..baselines import run_args
from ..config import ConfigError, RunConfig, UserError
from ..degrees import LAM_GRIDS
from ..run import RunDir
from ..run.layout import fail_suffix
from ..schemes import get
from ..schemes.families import rate_suffix
from ..schemes.searched import SEARCH_KEYS, search_overrides
from ..stats import mean_ci
from ..utils.console import clock, log, say
from ..utils.cpu import runtime
from ..utils.io import write_csv, write_json
from ..utils.lock import Busy
from . import RunInfo
from .select import _table_rows, choose, point_name, print_selection, retrain_job, search_job

EXTRA = "neurosym tune needs the tune extra: pip install -e '.[tune]' in the neurosym checkout (or pip install " \
        "optuna cmaes)"
WAIT = 10.0
"""seconds between looks at a program or model another process is making (its lock, utils/lock.Busy)"""
CREATE_TRIES = 5
"""attempts at opening a database whose tables another process is creating at the same moment"""
FAILS_IN_A_ROW = 3
"""trials of this process that may fail one after another before the command stops with the last one's line"""
RULE = ("lowest mean validation loss after retraining; among the retrained trials whose paired 95% interval of the "
        "loss difference to it contains 0, the lowest max in+out (select's rule)")


def _optuna():
    try:
        import optuna
    except ImportError:
        raise UserError(EXTRA) from None
    optuna.logging.set_verbosity(optuna.logging.WARNING)  # this module says what each trial did
    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    return optuna


# ------------------------------------------------------------------------------------------------- the space
def space(cfg: RunConfig) -> dict[str, Any]:
    """The search space: lam [low, high] and its step, K [low, high], the feature maps, the rate [low, high]."""
    t = cfg.tune
    lam = list(t.lam) or [min(LAM_GRIDS[cfg.synth.objective]), max(LAM_GRIDS[cfg.synth.objective])]
    n = cfg.task.max_agents
    if t.rules[1] >= n:
        raise ConfigError(f"tune.rules reaches K={t.rules[1]}, but an agent of {cfg.task.name} has at most {n - 1} "
                          f"others; e.g. tune.rules=[{min(t.rules[0], n - 1)},{n - 1}]")
    return {"lam": lam, "lam_step": t.lam_step, "rules": list(t.rules), "features": list(t.features),
            "retrain_lr": list(t.retrain_lr)}


def trial_point(trial, cfg: RunConfig, sp: dict[str, Any]) -> RunConfig:
    """The prog config of a trial's draw (select's grid point, with the rate), values as the trial runs them: lam
    and the rate rounded (6 and 2 significant digits), so the names on disk stay short."""
    lam = trial.suggest_float("lam", *sp["lam"], step=sp["lam_step"])
    k = trial.suggest_int("rules", *sp["rules"])
    f = trial.suggest_categorical("features", sp["features"])
    lr = trial.suggest_float("retrain_lr", *sp["retrain_lr"], log=True)
    return dataclasses.replace(cfg, rules=k, lam=float(f"{lam:.6g}"), features=f, baseline=get("prog"), cmd="synth",
                               optim=dataclasses.replace(cfg.optim, retrain_lr=float(f"{lr:.2g}")))


def trial_name(point: RunConfig) -> str:
    """A trial's row: its program's tag and, when not the default, its rate (k2-lam0.45-v1-...-rlr0.0018)."""
    return point_name(point) + rate_suffix(point)


# ------------------------------------------------------------------------------------------------- the study
def study_key(cfg: RunConfig) -> dict[str, Any]:
    """Everything that sets a study's trials: the space, the sampler and pruner, and the task, budget, seed, model,
    optimiser (the rate aside: it is drawn) and search settings. Paths, devices and threads are not in it."""
    rec = cfg.record()
    optim = {k: v for k, v in rec["optim"].items() if k != "retrain_lr"}
    return {"space": space(cfg), "sampler": cfg.tune.sampler, "pruner": cfg.tune.pruner,
            "startup": cfg.tune.startup, "seed": cfg.seed, "task": rec["task"], "budget": rec["budget"],
            "model": rec["model"], "optim": optim, "synth": rec["synth"]}


def study_name(cfg: RunConfig) -> str:
    """tune.study, else <task>-<budget>-seed<k>-<sampler>-<10 hex of the key's SHA-1>."""
    if cfg.tune.study:
        return cfg.tune.study
    digest = hashlib.sha1(json.dumps(study_key(cfg), sort_keys=True).encode()).hexdigest()[:10]
    task = cfg.task.name + fail_suffix(cfg.task.link_failure)  # as its run directory's task folder
    return f"{task}-{cfg.budget.name}-seed{cfg.seed}-{cfg.tune.sampler}-{digest}"


def storage_url(cfg: RunConfig) -> str:
    return cfg.tune.storage or f"sqlite:///{RunDir(cfg).tune_db.absolute()}"


def shown(url: str) -> str:
    """A storage URL as logs and records show it: its password hidden."""
    try:
        from sqlalchemy.engine import make_url

        return make_url(url).render_as_string(hide_password=True)
    except Exception:
        return url.split("@")[-1] if "@" in url else url


def open_storage(optuna, url: str):
    """Optuna's RDB storage of ``url``, with heartbeats (a killed process's trials are failed and run again) and a
    minute's patience with a locked SQLite file; one line when it cannot be opened. Processes that open a new
    database at once race to create its tables (one finds a table made, or a row written, under it): the loser
    opens it again, as it does a server that does not answer yet."""
    from pathlib import Path

    from optuna import storages
    from sqlalchemy.exc import IntegrityError, OperationalError

    retry = ({"heartbeat_stale_trial_callback": storages.RetryHeartbeatStaleTrialCallback(max_retry=2)}
             if hasattr(storages, "RetryHeartbeatStaleTrialCallback")  # optuna >= 4.9; before: failed_trial_callback
             else {"failed_trial_callback": storages.RetryFailedTrialCallback(max_retry=2)})
    try:
        from sqlalchemy.engine import make_url

        parsed = make_url(url)
        sqlite = parsed.get_backend_name() == "sqlite"
        if sqlite and parsed.database not in (None, "", ":memory:"):
            Path(parsed.database).expanduser().parent.mkdir(parents=True, exist_ok=True)
        for attempt in range(CREATE_TRIES):
            try:
                return storages.RDBStorage(url, engine_kwargs={"connect_args": {"timeout": 60}} if sqlite else {},
                                           heartbeat_interval=60, grace_period=180, **retry)
            except (IntegrityError, OperationalError):  # another process's tables half made, or no answer yet
                if attempt + 1 == CREATE_TRIES:
                    raise
                time.sleep(0.5 * (attempt + 1))
    except Exception as e:  # a bad URL, a missing driver, a server that does not answer: the input's
        first = (str(e).strip().splitlines() or [type(e).__name__])[0]
        raise UserError(f"tune.storage={shown(url)} cannot be opened ({type(e).__name__}: {first}); give an "
                        "SQLAlchemy URL such as sqlite:////shared/tune.db or postgresql://user@host/db") from None


def sampler_seed(cfg: RunConfig, before: int) -> int:
    """The sampler's seed: from seed, tune.worker and the trials the study held when this process started, so a
    rerun and a second worker draw apart, and the same start draws the same."""
    return int.from_bytes(hashlib.sha256(f"{cfg.seed}/{cfg.tune.worker}/{before}".encode()).digest()[:4], "little")


SAMPLERS: dict[str, Callable] = {
    "tpe": lambda o, seed, n: o.samplers.TPESampler(seed=seed, n_startup_trials=n),
    "cmaes": lambda o, seed, n: o.samplers.CmaEsSampler(seed=seed, n_startup_trials=n,
                                                        warn_independent_sampling=False),
}
"""tune.sampler -> (optuna, seed, startup trials) -> the sampler (verb_config.SAMPLERS names them)"""
NEEDS = {"cmaes": "cmaes"}
"""tune.sampler -> the package it imports only when it first models the study (checked before any trial)"""
PRUNERS: dict[str, Callable] = {
    "median": lambda o, n: o.pruners.MedianPruner(n_startup_trials=n, n_warmup_steps=0),
    "none": lambda o, n: o.pruners.NopPruner(),
}
"""tune.pruner -> (optuna, startup trials) -> the pruner (verb_config.PRUNERS names them)"""


def open_study(optuna, cfg: RunConfig):
    """The study (created, or loaded to resume), its sampler seeded for this process; another study of the same
    name made with other settings is one line."""
    url, name = storage_url(cfg), study_name(cfg)
    storage = open_storage(optuna, url)
    key = json.loads(json.dumps(study_key(cfg)))
    need = NEEDS.get(cfg.tune.sampler)
    try:
        if need:
            importlib.import_module(need)
    except ImportError:
        raise UserError(f"tune.sampler={cfg.tune.sampler} needs the {need} package: {EXTRA}") from None
    study = optuna.create_study(storage=storage, study_name=name, direction="minimize", load_if_exists=True,
                                sampler=SAMPLERS[cfg.tune.sampler](optuna, 0, cfg.tune.startup),  # reseeded below
                                pruner=PRUNERS[cfg.tune.pruner](optuna, cfg.tune.startup))
    old = study.user_attrs.get("key")
    if old is None:
        study.set_user_attr("key", key)
    elif old != key:
        diff = _first_difference(old, key)
        raise ConfigError(f"study {name} in {shown(url)} was made with {diff}; name another one (tune.study=...) "
                          "or leave tune.study empty")
    before = len(study.get_trials(deepcopy=False))
    study.sampler = SAMPLERS[cfg.tune.sampler](optuna, sampler_seed(cfg, before), cfg.tune.startup)
    return study, name, url


def _first_difference(old: Any, new: Any, at: str = "") -> str:
    if isinstance(old, dict) and isinstance(new, dict):
        for k in sorted(set(old) | set(new)):
            if old.get(k) != new.get(k):
                return _first_difference(old.get(k), new.get(k), f"{at}{k}.")
    return f"{at.rstrip('.')}={old!r} (this run: {new!r})"


# ------------------------------------------------------------------------------------------------- the trials
def _when_free(fn: Callable, cfg: RunConfig, info: RunInfo) -> dict[str, Any]:
    """select's job ``fn``, waiting while another process makes the same program or model (it is then reused)."""
    while True:
        try:
            return fn(cfg, info)
        except Busy as e:
            log.info("%s; looking again in %g s", e, WAIT)
            time.sleep(WAIT)


def _mean(losses: list[float]) -> float:
    return mean_ci(losses)[0]


def objective(optuna, cfg: RunConfig, info: RunInfo, sp: dict[str, Any], outcomes: list[tuple[int, str, str]]):
    """The trial function: select's search job, the pruning point, select's retrain job; what each trial did is
    appended to ``outcomes`` as (number, complete | pruned | failed, what to log)."""
    def run(trial) -> float:
        point = trial_point(trial, cfg, sp)
        name = trial_name(point)
        trial.set_user_attr("name", name)
        trial.set_user_attr("retrain_lr", point.optim.retrain_lr)  # the rate it ran at (the param: as drawn)
        trial.set_user_attr("worker", cfg.tune.worker)
        what = f"{name} (K {point.rules}, lam {point.lam:g}, {point.features}, retrain lr {point.optim.retrain_lr:g})"
        try:
            prog = _when_free(search_job, point, info)
            trial.set_user_attr("prog", prog)
            trial.set_user_attr("labels", {"prog": RunDir(point).label, "retrained": RunDir(
                dataclasses.replace(point, baseline=get("prog-retrained"))).label})
            before = _mean(prog["loss"])
            trial.report(before, 0)
            if trial.should_prune():
                outcomes.append((trial.number, "pruned", f"{what}: pruned before retraining, its program's "
                                 f"validation loss {before:.3f} is worse than the median of the finished trials'"))
                raise optuna.TrialPruned()
            ret = _when_free(retrain_job, point, info)
        except UserError as e:
            trial.set_user_attr("error", str(e))
            outcomes.append((trial.number, "failed", f"{what}: failed: {e}"))
            raise
        trial.set_user_attr("retrained", ret)
        after = _mean(ret["loss"])
        outcomes.append((trial.number, "complete", f"{what}: validation loss {after:.3f} after retraining "
                                                   f"({before:.3f} before)"))
        return after

    return run


def run_trials(optuna, study, cfg: RunConfig, info: RunInfo) -> int:
    """Trials until the study holds tune.trials finished ones (running ones of other processes counted); returns
    how many this process ran. FAILS_IN_A_ROW failures in a row stop it with the last one's line."""
    from optuna.storages import fail_stale_trials
    from optuna.trial import TrialState

    sp, outcomes, in_a_row = space(cfg), [], 0
    fn = objective(optuna, cfg, info, sp, outcomes)
    t0 = time.perf_counter()
    while True:
        fail_stale_trials(study)  # a killed process's trials: failed, and queued again (open_storage)
        states = Counter(t.state for t in study.get_trials(deepcopy=False))
        finished = states[TrialState.COMPLETE] + states[TrialState.PRUNED]
        if finished + states[TrialState.RUNNING] >= cfg.tune.trials:
            return len(outcomes)
        study.optimize(fn, n_trials=1, catch=(UserError,), gc_after_trial=False)
        number, state, line = outcomes[-1]
        in_a_row = in_a_row + 1 if state == "failed" else 0
        say(f"trial {number} ({finished + (state != 'failed')}/{cfg.tune.trials} finished, "
            f"{clock(time.perf_counter() - t0)}): {line}")
        if in_a_row >= FAILS_IN_A_ROW:
            raise UserError(f"{FAILS_IN_A_ROW} trials in a row failed, the last with: {line}")


# ------------------------------------------------------------------------------------------------- the table
def study_rows(optuna, study) -> tuple[list[dict], list[dict], dict[str, dict]]:
    """select's rows of the study's finished trials, one per distinct (program, rate): its program's validation
    (``choose``d, as select's programs) and, for those retrained, the retrained validation (``choose``d, as
    select's finalists); and per name its trial numbers, state, rate and labels."""
    from optuna.trial import TrialState

    meta: dict[str, dict] = {}
    for t in sorted(study.get_trials(deepcopy=False), key=lambda t: t.number):
        if t.state not in (TrialState.COMPLETE, TrialState.PRUNED) or "prog" not in t.user_attrs:
            continue
        m = meta.setdefault(t.user_attrs["name"], {"trials": [], "prog": t.user_attrs["prog"], "retrained": None,
                                                  "labels": t.user_attrs["labels"], "params": t.params,
                                                  "retrain_lr": t.user_attrs["retrain_lr"]})
        m["trials"].append(t.number)
        if t.state == TrialState.COMPLETE and m["retrained"] is None:
            m["retrained"] = t.user_attrs["retrained"]
    if not meta:
        return [], [], meta
    first = choose([{**m["prog"], "name": n} for n, m in meta.items()])
    done = [{**m["retrained"], "name": n} for n, m in meta.items() if m["retrained"] is not None]
    return first, choose(done) if done else [], meta


def eval_line(cfg: RunConfig, row: dict[str, Any]) -> str:
    """The command that evaluates a trial's retrained model on the test seeds."""
    point = dataclasses.replace(cfg, rules=row["rules"], lam=row["lam"], features=row["features"],
                                optim=dataclasses.replace(cfg.optim, retrain_lr=row["retrain_lr"]))
    rate = f" optim.retrain_lr={row['retrain_lr']:g}" if rate_suffix(point) else ""
    return (f"neurosym eval {run_args(cfg)} baseline=prog-retrained rules={row['rules']} lam={row['lam']:g} "
            f"features={row['features']}" + search_overrides(point) + rate)


def write_study(optuna, study, cfg: RunConfig, name: str, url: str, ran: int, seconds: float) -> dict[str, Any]:
    """select/tune/<study>/selection.csv and .json (select's table, with each row's rate, trials and state) and
    pareto.csv/.png (every program's and retrained model's validation loss against max in+out); the table on
    screen. Returns the pick (select's rule among the retrained trials) and the study's best."""
    from .results import write_pareto

    first, final, meta = study_rows(optuna, study)
    if not first:
        raise UserError(f"study {name} in {shown(url)} has no finished trial yet; run it with tune.trials=N (N > 0)")
    table = _table_rows(first, final)
    for r in table:
        m = meta[r["name"]]
        r.update(retrain_lr=m["retrain_lr"], trials=" ".join(map(str, m["trials"])), state="complete" if m["retrained"] else "pruned")
    by_name = {r["name"]: r for r in table}
    pick = next((r for r in final if r["picked"]), None)
    best = next((r for r in final if r["best"]), None)
    out = RunDir(cfg).study_dir(name)
    counts = Counter(t.state.name.lower() for t in study.get_trials(deepcopy=False))
    choice = None if pick is None else {**{k: by_name[pick["name"]][k] for k in ("name", "rules", "lam", "features",
                                                                              "retrain_lr", "trials")},
                                        "val_loss": pick["loss_mean"], "max_degree": pick["degree"],
                                        "eval": eval_line(cfg, by_name[pick["name"]])}
    record = {"command": "tune", "version": __version__, "task": cfg.task.name, "seed": cfg.seed,
              "budget": cfg.budget.name, "study": name, "storage": shown(url), "key": study_key(cfg),
              "sampler": cfg.tune.sampler, "pruner": cfg.tune.pruner, "trials": dict(counts), "ran_here": ran,
              "picked": choice, "rule": RULE,
              "best": None if best is None else {"name": best["name"], "val_loss": best["loss_mean"],
                                                 "trials": meta[best["name"]]["trials"],
                                                 "params": meta[best["name"]]["params"]},
              "synth": {k: getattr(cfg.synth, k) for k in SEARCH_KEYS}, "val_seeds": cfg.budget.val_seeds,
              "programs": first, "retrained": final, "seconds_here": seconds, "runtime": runtime(),
              "config": cfg.record()}
    write_csv(RunDir(cfg).study_file(name, ".csv"), table)
    write_json(RunDir(cfg).study_file(name), record)
    points = {m["labels"]["prog"]: (first_row["degree"], first_row["loss_mean"])
              for first_row in first for m in [meta[first_row["name"]]]}
    points.update({meta[r["name"]]["labels"]["retrained"]: (r["degree"], r["loss_mean"]) for r in final})
    write_pareto([(label, {"max_degree": {"mean": d}, "cost": {"mean": loss}}) for label, (d, loss) in points.items()],
                 out, f"{cfg.task.name} ({cfg.budget.name}, seed {cfg.seed}): study {name}, validation seeds",
                 cfg.plots)
    print_selection(table, cfg, None if pick is None else pick["name"], None)
    return record


def run_tune(cfg: RunConfig, info: RunInfo) -> dict[str, Any]:
    """The whole study (module docstring): resume or start it, run trials up to tune.trials, write its table."""
    from ..run.checkpoints import open_checkpoint

    optuna = _optuna()
    space(cfg)  # a bad space is reported before a missing artifact
    open_checkpoint(cfg, oracle=True)  # fail early: every trial starts from the oracle
    study, name, url = open_study(optuna, cfg)
    held = len(study.get_trials(deepcopy=False))
    say(f"tune {cfg.task.name}: study {name} in {shown(url)} ({held} trial(s) so far, target {cfg.tune.trials} "
        f"finished), sampler {cfg.tune.sampler}, pruner {cfg.tune.pruner}, worker {cfg.tune.worker}")
    t0 = time.perf_counter()
    ran = run_trials(optuna, study, cfg, info)
    record = write_study(optuna, study, cfg, name, url, ran, time.perf_counter() - t0)
    pick = record["picked"]
    out = RunDir(cfg).study_dir(name)
    if pick is None:
        say(f"[yellow]no trial of study {name} was retrained yet[/] (all pruned); the table is in {out}")
        return {"study": name, "trials": record["trials"]}
    say(f"[green]tuned[/] study {name}: {sum(record['trials'].values())} trial(s), {ran} run here "
        f"({clock(time.perf_counter() - t0)}); select's rule picks {pick['name']} (validation loss "
        f"{pick['val_loss']:.3f}) -> {out}; `{pick['eval']}` evaluates it on the test seeds")
    return {"selected": pick["name"], "loss": pick["val_loss"], "study": name}
