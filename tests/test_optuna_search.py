"""`neurosym tune`: select's choice by an Optuna study in a real SQLite storage, resumed and shared; its sampler, its
pruning before retraining, its one-line errors, and the names of models retrained at another rate."""

import csv
import json
import sys

import pytest

from test_cli import run

COMMON = ["task=two-groups-cross", "budget=tiny", "budget.val_seeds=3"]
SPACE = ["tune.rules=[1,2]", "tune.features=[v1]"]  # two-groups-cross at tiny has 3 agents a group


def _optuna():
    return pytest.importorskip("optuna", reason="neurosym tune needs the tune extra (pip install -e '.[tune]')")


def _cfg(tmp_path, *extra):
    from neurosym_cli.commands.apps import compose_config

    return compose_config("tune", [f"runs_root={tmp_path}", *COMMON, *SPACE, *extra])


def _trials(optuna, cfg):
    from neurosym_cli.stages.tune import storage_url, study_name

    return optuna.load_study(study_name=study_name(cfg), storage=storage_url(cfg)).get_trials()


def test_a_study_runs_resumes_and_is_shared_by_a_second_worker(tmp_path):
    optuna = _optuna()
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.stages import RunInfo
    from neurosym_cli.stages.train import train
    from neurosym_cli.stages.tune import run_tune, study_name

    train(compose_config("train", [f"runs_root={tmp_path}", *COMMON]), RunInfo())
    cfg = _cfg(tmp_path, "tune.trials=2")
    run_tune(cfg, RunInfo())
    exp = tmp_path / "two-groups-cross/tiny/seed0"
    assert (exp / "select/tune/optuna.db").is_file()  # the default storage, under the run directory
    before = {t.number: (t.params, t.value) for t in _trials(optuna, cfg)}
    assert len(before) == 2 and all(v is not None for _, v in before.values())

    out = exp / "select/tune" / study_name(cfg)
    with open(out / "selection.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert 1 <= len(rows) <= 2 and {"val_loss", "retrained_val_loss", "picked", "retrain_lr", "trials"} <= set(rows[0])
    assert sum(r["picked"] == "True" for r in rows) == 1
    sel = json.loads((out / "selection.json").read_text())
    assert sel["trials"] == {"complete": 2} and sel["picked"]["name"] in {r["name"] for r in rows}
    assert "neurosym eval" in sel["picked"]["eval"] and "baseline=prog-retrained" in sel["picked"]["eval"]
    assert (out / "pareto.csv").is_file()

    # a rerun with a larger target resumes the study: the earlier trials kept, one more run
    more = _cfg(tmp_path, "tune.trials=3")
    assert study_name(more) == study_name(cfg)
    run_tune(more, RunInfo())
    after = {t.number: (t.params, t.value) for t in _trials(optuna, cfg)}
    assert len(after) == 3 and all(after[n] == before[n] for n in before)
    # a second worker on the same study (what a SLURM array task runs): the same study, its own draws
    other = _cfg(tmp_path, "tune.trials=4", "tune.worker=1")
    assert study_name(other) == study_name(cfg)
    run_tune(other, RunInfo())
    trials = _trials(optuna, cfg)
    assert len(trials) == 4 and [t.user_attrs["worker"] for t in trials] == [0, 0, 0, 1]
    sel = json.loads((out / "selection.json").read_text())
    assert sum(sel["trials"].values()) == 4 and sel["ran_here"] == 1
    run_tune(other, RunInfo())  # the target reached: nothing more is run
    assert len(_trials(optuna, cfg)) == 4


def test_the_sampler_is_seeded_and_workers_draw_apart(tmp_path):
    optuna = _optuna()
    from neurosym_cli.errors import ConfigError
    from neurosym_cli.stages.tune import open_study, space, trial_point

    def draws(*extra):
        cfg = _cfg(tmp_path, "tune.features=[v1,v2]", *extra)
        study, _, _ = open_study(optuna, cfg)
        return [trial_point(study.ask(), cfg, space(cfg)) for _ in range(3)]

    def key(points):
        return [(p.rules, p.lam, p.features, p.optim.retrain_lr) for p in points]

    a = key(draws("tune.study=a"))
    assert a == key(draws("tune.study=b"))  # the same seed and start: the same draws
    assert a != key(draws("tune.study=c", "tune.worker=1"))
    assert a != key(draws("tune.study=d", "seed=1"))
    assert all(0.3 <= lam <= 1.0 and 3e-4 <= lr <= 3e-3 and k in (1, 2) for k, lam, _, lr in a)
    cma = key(draws("tune.study=e", "tune.sampler=cmaes"))
    assert cma == key(draws("tune.study=f", "tune.sampler=cmaes"))
    with pytest.raises(ConfigError, match="study a in .* was made with space.lam"):
        draws("tune.study=a", "tune.lam=[0.1,0.2]")  # a study of that name with another space


def test_a_trial_worse_than_the_median_is_pruned_before_retraining(tmp_path, monkeypatch):
    optuna = _optuna()
    import neurosym_cli.stages.tune as tune
    from neurosym_cli.stages import RunInfo

    cfg = _cfg(tmp_path, "tune.startup=1")
    losses, retrained = iter([[1.0, 1.1, 0.9], [5.0, 5.1, 4.9], [0.5, 0.6, 0.4]]), []

    def search_job(point, info):
        return {"name": tune.point_name(point), "loss": next(losses)}

    def retrain_job(point, info):
        retrained.append(point.lam)
        return {"name": tune.point_name(point), "loss": [0.1, 0.2, 0.3]}

    monkeypatch.setattr(tune, "search_job", search_job)
    monkeypatch.setattr(tune, "retrain_job", retrain_job)
    study, _, _ = tune.open_study(optuna, cfg)
    outcomes = []
    fn = tune.objective(optuna, cfg, RunInfo(), tune.space(cfg), outcomes)
    for _ in range(3):
        study.optimize(fn, n_trials=1)
    assert [s for _, s, _ in outcomes] == ["complete", "pruned", "complete"]
    assert len(retrained) == 2  # the pruned trial was never retrained
    states = [t.state for t in study.get_trials()]
    assert states == [optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.PRUNED,
                      optuna.trial.TrialState.COMPLETE]
    assert study.get_trials()[1].intermediate_values == {0: pytest.approx(5.0)}


def test_a_trial_waits_for_a_program_another_process_is_making(tmp_path, monkeypatch):
    """Two workers that draw the same program: the second waits for the first's lock, then reuses its result."""
    import threading

    import neurosym_cli.stages.tune as tune
    from neurosym_cli.utils.lock import run_lock

    monkeypatch.setattr(tune, "WAIT", 0.05)
    where, calls, held, release = tmp_path / "synth/k1-lam0.5-v1", [], threading.Event(), threading.Event()

    def job(cfg, info):
        calls.append(1)
        with run_lock(where):
            return {"made": True}

    def other_process():
        with run_lock(where):
            held.set()
            release.wait(10)

    t = threading.Thread(target=other_process)
    t.start()
    held.wait(10)
    threading.Timer(0.3, release.set).start()
    assert tune._when_free(job, None, None) == {"made": True}
    t.join()
    assert len(calls) >= 2  # refused (Busy) while the other held it, then made


def test_a_missing_optuna_or_a_bad_storage_is_one_line(tmp_path, monkeypatch):
    from neurosym_cli.errors import UserError
    from neurosym_cli.stages import RunInfo
    from neurosym_cli.stages.tune import run_tune

    with monkeypatch.context() as m:
        m.setitem(sys.modules, "optuna", None)  # import optuna fails
        with pytest.raises(UserError, match=r"needs the tune extra: pip install -e '\.\[tune\]'"):
            run_tune(_cfg(tmp_path), RunInfo())  # before any missing oracle is reported
    optuna = _optuna()
    from neurosym_cli.stages.tune import open_storage, open_study

    with monkeypatch.context() as m:
        m.setitem(sys.modules, "cmaes", None)  # CMA-ES would fail only at its first modelled draw
        with pytest.raises(UserError, match=r"tune.sampler=cmaes needs the cmaes package: .*\.\[tune\]"):
            open_study(optuna, _cfg(tmp_path, "tune.sampler=cmaes"))

    with pytest.raises(UserError, match=r"tune.storage=nosuchdb://host/x cannot be opened"):
        open_storage(optuna, "nosuchdb://host/x")
    with pytest.raises(UserError, match=r"postgresql://u:\*\*\*@"):  # the password is never printed
        open_storage(optuna, "postgresql://u:secret@127.0.0.1:1/x")


def test_a_bad_sampler_is_one_line(tmp_path):
    p = run(["tune", *COMMON, "tune.sampler=grid"], tmp_path, check=False)
    assert p.returncode == 2 and p.stderr.strip().count("\n") == 0
    assert "tune.sampler must be one of tpe, cmaes, got 'grid'" in p.stderr


def test_a_model_retrained_at_another_rate_has_its_own_names(tmp_path):
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.run import RunDir, retrain_command

    base = [f"runs_root={tmp_path}", "task=two-groups-cross", "budget=tiny", "rules=2", "lam=0.5"]
    default = compose_config("retrain", base)
    tag = RunDir(default).program_tag  # k2-lam0.5-v1 and the search's variant
    assert tag.startswith("k2-lam0.5-v1")
    assert RunDir(default).model_name == f"retrained-{tag}"  # every earlier run's name
    assert RunDir(default).label == f"prog-retrained-{tag}" and "retrain_lr" not in retrain_command(default)
    other = compose_config("retrain", [*base, "optim.retrain_lr=0.003"])
    assert RunDir(other).program_tag == tag  # the program is the same one
    assert RunDir(other).model_name == f"retrained-{tag}-rlr0.003"
    assert RunDir(other).label == f"prog-retrained-{tag}-rlr0.003"
    assert retrain_command(other).endswith(" optim.retrain_lr=0.003")


@pytest.mark.slow
def test_two_processes_of_a_joblib_sweep_share_one_study(tmp_path):
    optuna = _optuna()
    run(["train", *COMMON], tmp_path)
    p = run(["tune", "-m", *COMMON, *SPACE, "tune.trials=4", "tune.worker=0,1", "hydra/launcher=joblib",
             "hydra.launcher.n_jobs=2"], tmp_path, timeout=600)
    trials = _trials(optuna, _cfg(tmp_path, "tune.trials=4"))
    finished = [t for t in trials if t.state.is_finished() and t.state != optuna.trial.TrialState.FAIL]
    assert len(finished) >= 4 and {t.user_attrs["worker"] for t in trials} <= {0, 1}, p.stdout[-2000:]
    print("trials per worker:", {w: sum(t.user_attrs["worker"] == w for t in trials) for w in (0, 1)})


@pytest.mark.slow
def test_two_slurm_jobs_share_one_study(tmp_path):
    """The cluster path: submitit's local executor runs each tune.worker as its own job, as SLURM would on many
    machines (hydra/launcher=slurm_local, the cluster extra), all on one SQLite study."""
    pytest.importorskip("hydra_plugins.hydra_submitit_launcher", reason="the cluster extra (submitit launcher)")
    optuna = _optuna()
    run(["train", *COMMON], tmp_path)
    p = run(["tune", "-m", *COMMON, *SPACE, "tune.trials=4", "tune.worker=0,1", "hydra/launcher=slurm_local"],
            tmp_path, timeout=900)
    trials = _trials(optuna, _cfg(tmp_path, "tune.trials=4"))
    finished = [t for t in trials if t.state.is_finished() and t.state != optuna.trial.TrialState.FAIL]
    assert len(finished) >= 4 and {t.user_attrs["worker"] for t in trials} == {0, 1}, p.stdout[-2000:]
