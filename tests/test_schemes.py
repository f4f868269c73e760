"""The communication schemes: the registry's contract (every scheme answers every question, its stage plan runs),
and the two follow-up baselines, expo (ExpoComm's exponential graph) and comm-range (hear everyone within r)."""

import json
import os
import subprocess

import pytest
import torch

from conftest import neurosym_cmd
from neurosym_cli.run import RunDir, synth_command, train_command
from neurosym_cli.run.models import scheme_provider
from neurosym_cli.baselines import VERBS, Artifact, BaselineConfig, Stage
from neurosym_cli.commands.apps import compose_config
from neurosym_cli.config import UserError
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.dsl.interpret import picks_to_mask
from neurosym_cli.tasks import Rng, make_task
from neurosym_cli.tasks.formation import FormationState
from neurosym_cli.policy.comm import CommContext, LinkFailure
from neurosym_cli.schemes import SCHEMES, default_baselines, get, model_baseline, rank
from neurosym_cli.stages.graph import plan, requires, upstream
from neurosym_cli.stages.synth import SYNTHESIZERS
from plugin_schemes import ALL_SCHEMES, use


def _ctx(n: int, step: int = 0, batch: int = 3, seed: int = 0) -> CommContext:
    env = make_task(CrossConfig(name="c", noise_std=0.0))
    g = torch.Generator().manual_seed(seed)
    pos = torch.rand(batch, n, 2, generator=g) * 4  # a crowd: some pairs within 1.5, some not
    state = FormationState(pos, pos.clone(), torch.zeros(batch, n, dtype=torch.long))
    return CommContext(env, state, env.observe(state, Rng(g)), Rng(g), step)


# --- expo --------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("n", [2, 5, 8, 40])
def test_expo_hears_exactly_one_and_is_heard_by_exactly_one(n):
    for step in range(8):
        ctx = _ctx(n, step)
        pk = get("expo").picks(ctx, 0)
        assert pk.shape == (3, n, 1)
        mask = get("expo").select(ctx, torch.zeros(3, n, n), 0)
        assert torch.equal(mask, picks_to_mask(pk, n))
        assert mask.sum(2).eq(1).all() and mask.sum(1).eq(1).all()  # in- and out-degree 1
        assert not mask.diagonal(dim1=1, dim2=2).any()


def test_expo_peers_cycle_through_the_powers_of_two_with_the_step():
    # N = 5: ceil(log2 5) = 3, so the offsets 1, 2, 4 repeat every three steps; N = 8: 1, 2, 4 as well
    for n, offsets in ((5, [1, 2, 4, 1, 2, 4, 1]), (8, [1, 2, 4, 1, 2, 4, 1]), (2, [1, 1, 1])):
        for t, off in enumerate(offsets):
            pk = get("expo").picks(_ctx(n, t, batch=1), round=0)[0, :, 0]
            assert pk.tolist() == [(i + off) % n for i in range(n)], (n, t)
    # both rounds of a step hear the same peer (k cycles with the step, not the round)
    ctx = _ctx(5, 1)
    assert torch.equal(get("expo").picks(ctx, 0), get("expo").picks(ctx, 1))


def test_expo_degrees_in_a_rollout_are_one_every_step():
    from neurosym_cli.config import ModelConfig
    from neurosym_cli.policy import CommTransformer
    from neurosym_cli.rollout import rollout

    task = compose_config("train", ["task=random-cross"]).task
    env = make_task(task, 12)
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, task.rounds, ModelConfig())
    g = torch.Generator().manual_seed(0)
    with torch.no_grad():
        for bucket in env.reset(6, g):
            traj = rollout(env, pol, get("expo"), bucket, Rng(g), 12)
            assert traj.max_in.eq(1).all() and traj.max_out.eq(1).all() and traj.mean_degree.eq(2).all()


# --- comm-range --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("radius", [0.5, 1.5, 3.0, 100.0])
def test_comm_range_is_the_brute_force_radius_mask(radius):
    scheme = dataclasses_replace(get("comm-range"), radius=radius)
    ctx = _ctx(12)
    pos = ctx.state.pos
    want = torch.zeros(3, 12, 12, dtype=torch.bool)
    for b in range(3):
        for i in range(12):
            for j in range(12):
                want[b, i, j] = i != j and float(torch.linalg.norm(pos[b, i] - pos[b, j])) <= radius
    assert torch.equal(scheme.mask(ctx, 0), want)
    pk = scheme.picks(ctx, 0)  # the sparse path: padded to the largest degree, -1 = nobody
    assert pk.shape[-1] == int(want.sum(-1).max())
    assert torch.equal(picks_to_mask(pk, 12), want)
    assert torch.equal(scheme.select(ctx, torch.zeros(3, 12, 12), 0), want)
    # a failed link drops a heard agent, never adds one
    lossy = LinkFailure(scheme, 0.5).picks(ctx, 0)
    assert not (picks_to_mask(lossy, 12) & ~want).any()


def test_comm_range_names_its_radius_and_refuses_a_bad_one():
    cfg = compose_config("train", ["task=random-cross", "budget=tiny", "baseline=comm-range", "baseline.radius=2"])
    assert cfg.baseline.radius == 2.0
    assert RunDir(cfg).model_name == "comm-range-r2" == RunDir(cfg).label
    assert train_command(cfg).endswith("baseline=comm-range budget=tiny seed=0 baseline.radius=2")
    assert RunDir(compose_config("eval", ["baseline=comm-range"])).model_name == "comm-range-r1.5"
    with pytest.raises(UserError, match="baseline.radius must be positive"):
        compose_config("train", ["baseline=comm-range", "baseline.radius=0"])


def dataclasses_replace(obj, **kw):
    import dataclasses

    return dataclasses.replace(obj, **kw)


# --- the registry's contract ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ALL_SCHEMES)
def test_every_scheme_answers_every_question(name, tmp_path, monkeypatch):
    use(name, monkeypatch)  # the example plugin (examples/schemes) beside the built-in ones
    cfg = compose_config("eval", ["task=random-cross", "budget=tiny", f"baseline={name}", f"runs_root={tmp_path}"])
    b = cfg.baseline
    assert isinstance(b, BaselineConfig) and type(b) is type(SCHEMES[name]) and b == SCHEMES[name]
    assert b.name == name and b.description and isinstance(b.pipeline, bool)
    assert isinstance(b.has_program, bool) and isinstance(b.soft_attention, bool)
    assert b.label(cfg).startswith(name) and b.model_dir(cfg)
    art = b.artifact(cfg)
    assert art is None or (isinstance(art, Artifact) and art.file in SYNTHESIZERS and art.tag)
    assert b.has_program <= (art is not None and art.file == "program.txt")
    # its upstream: what graph.py runs for it, each stage after what it waits for, its weights' stage last but synth
    ups = b.upstream()
    assert ups == upstream(name) and ups and b.weights() in ups
    for k, stage in enumerate(ups):
        assert stage.verb in VERBS[:-1]
        assert all(dep in ups[:k] for dep in requires(stage)), stage
        # the command line of every upstream stage is the one its baseline= makes, and names the verb
        line = get(stage.baseline).command(stage.verb, cfg)
        assert line.startswith(f"neurosym {stage.verb} task=random-cross "), line
    assert (art is not None) == any(s.verb == "synth" for s in ups)
    assert train_command(cfg).startswith(f"neurosym {b.weights().verb} ")
    if art is not None:  # the same search makes the artifact of prog and of prog-retrained
        assert synth_command(cfg) == get(next(s for s in ups if s.verb == "synth").baseline).command("synth", cfg)
    # the report finds its training curves by the model directory it names
    found, retrained = model_baseline(b.model_dir(cfg))
    assert retrained == (b.weights().verb == "retrain")
    assert found == (b.weights().baseline if b.weights().verb == "train" else name)
    assert rank(name) == list(SCHEMES).index(name)
    # the provider is built from the config alone where there is no artifact to read; else a one-line error
    env = make_task(cfg.task, cfg.horizon)
    if art is None:
        comm = b.provider(cfg, env)
        assert callable(comm.select) and callable(comm.picks)
    else:
        with pytest.raises(UserError):  # nothing synthesized in this empty run directory: its file, as run/ names it
            b.provider(cfg, env, artifact=RunDir(cfg).artifact_file())
        with pytest.raises(UserError):
            scheme_provider(cfg, env)  # the same, through the run directory
        with pytest.raises(TypeError, match="artifact="):  # a scheme never guesses where its artifact lives
            b.provider(cfg, env)


@pytest.mark.parametrize("name", ALL_SCHEMES)
def test_the_plan_of_every_baseline_runs(name, monkeypatch):
    use(name, monkeypatch)
    stages = plan([name])
    assert stages[-1] == Stage("eval", name) and len(stages) == len(set(stages))
    for k, s in enumerate(stages):
        assert all(dep in stages[:k] for dep in requires(s)), s


def test_follow_ups_are_not_in_the_pipelines_default():
    assert "expo" not in default_baselines() and "comm-range" not in default_baselines()
    assert default_baselines() == ["tf-full", "hard-attn", "dist", "prog", "prog-retrained", "det-prog",
                                   "det-prog-retrained", "dt", "dt-retrained", "no-comm"]
    assert compose_config("pipeline").baselines == default_baselines()
    assert upstream("expo") == [Stage("train", "expo")] and upstream("comm-range") == [Stage("train", "comm-range")]


def test_override_checker_knows_each_schemes_own_fields():
    from neurosym_cli.overrides import check

    assert check(["baseline=comm-range", "baseline.radius=2.5"]) is None
    assert "did you mean 'baseline.radius'" in check(["baseline.radiu=2"])
    assert "takes a number" in check(["baseline.radius=far"])


# --- the CLI -----------------------------------------------------------------------------------------------------

def test_pipeline_with_expo_and_comm_range_tiny(tmp_path):
    env = {**os.environ, "NEUROSYM_RUNS": str(tmp_path)}
    p = subprocess.run([*neurosym_cmd(), "pipeline", "task=random-cross", "budget=tiny",
                        "baselines=[tf-full,expo,comm-range]", "plots=false"], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    table = p.stdout[p.stdout.rindex("tf-full"):]
    assert "expo" in table and "comm-range-r1.5" in table
    exp = tmp_path / "random-cross" / "tiny" / "seed0"
    assert (exp / "train" / "expo" / "model.pt").exists() and (exp / "train" / "comm-range-r1.5" / "model.pt").exists()
    m = json.loads((exp / "eval" / "expo" / "metrics.json").read_text())
    assert m["baseline"] == "expo" and m["summary"]["max_in"]["mean"] == pytest.approx(1.0)
    assert m["summary"]["max_out"]["mean"] == pytest.approx(1.0)
    m = json.loads((exp / "eval" / "comm-range-r1.5" / "metrics.json").read_text())
    assert m["baseline"] == "comm-range"
