"""VMAS scenarios as tasks (neurosym_cli/tasks/vmas/, docs/vmas.md): nested task names, gradients from the cost
through VMAS's physics to the policy's parameters, seeded determinism, the pipeline end to end, a user's own
BaseScenario from outside the package through train/synth/eval, and the one-line refusals. The task contract
itself runs over the VMAS tasks in tests/test_tasks.py. Tests that need VMAS skip when the extra is missing."""

import json
import sys
import textwrap
from importlib.util import find_spec

import pytest
import torch

from conftest import PAPER_METHOD, run_dir
from test_plugins import one_line, run

needs_vmas = pytest.mark.skipif(find_spec("vmas") is None,
                                reason="the vmas extra is not installed (pip install -e '.[vmas]')")
COMMON = ["budget=tiny", "plots=false", "threads=1"]


def _cfg(name="vmas/navigation", **over):
    from neurosym_cli.commands.apps import compose_config

    return compose_config("train", [f"task={name}", *[f"task.{k}={v}" for k, v in over.items()]]).task


def _task(name="vmas/navigation", horizon=None, **over):
    from neurosym_cli.tasks import make_task

    return make_task(_cfg(name, **over), horizon)


# ------------------------------------------------------------------------------------ nested task names
def test_nested_task_yamls_are_choices(tmp_path):
    """task/vmas/navigation.yaml is the option `vmas/navigation` (Hydra's nested name), in the package and in a
    user's config directory; its defaults list resolves relative to its own folder."""
    from neurosym_cli.choices import check_choices
    from neurosym_cli.tasks.registry import task_choices, yaml_target

    assert {"vmas/navigation", "vmas/dispersion", "random-cross"} <= set(task_choices())
    assert yaml_target("vmas/navigation") == "neurosym_cli.tasks.vmas.VmasTask"
    assert check_choices(["task=vmas/navigation"]) is None
    assert "vmas/navigation" in check_choices(["task=vmas/navigaton"])
    (tmp_path / "task" / "mine").mkdir(parents=True)
    (tmp_path / "task" / "mine" / "base.yaml").write_text("_target_: mymod.Task\nname: base\n")
    (tmp_path / "task" / "mine" / "big.yaml").write_text("defaults:\n  - base\n  - _self_\nname: big\n")
    args = ["--config-dir", str(tmp_path)]
    assert "mine/big" in task_choices(args) and yaml_target("mine/big", args) == "mymod.Task"


# --------------------------------------------------------------------------------------------- the adapter
@needs_vmas
def test_gradients_flow_from_the_cost_through_vmas_to_the_policy():
    """BPTT: the summed cost of a rollout through VMAS's physics reaches every parameter of the transformer, and an
    early action's gradient comes through later steps of the simulator."""
    from neurosym_cli.config import ModelConfig
    from neurosym_cli.policy import CommTransformer, FullComm
    from neurosym_cli.rollout import rollout
    from neurosym_cli.tasks import Rng

    task = _task(horizon=6)
    torch.manual_seed(0)
    pol = CommTransformer.for_task(task, ModelConfig(dropout=0.0))
    gen = torch.Generator().manual_seed(0)
    state = task.reset(3, gen)[0]
    traj = rollout(task, pol, FullComm(), state, Rng(gen), 6, stats=False)
    traj.cost.sum().backward()
    for name, p in pol.named_parameters():
        assert p.grad is not None and torch.isfinite(p.grad).all() and p.grad.abs().sum() > 0, name
    # the graph runs through the integrator: the first action moves the last positions
    s = task.reset(1, gen)[0]
    a = torch.zeros(1, s.n_agents, 2, requires_grad=True)
    s1 = task.step(s, a)
    for _ in range(4):
        s1 = task.step(s1, torch.zeros(1, s.n_agents, 2))
    g, = torch.autograd.grad(task.cost(s1, a).sum(), a)
    assert g.abs().sum() > 0
    assert not s.pos.requires_grad  # the old state's tensors are untouched (VMAS writes copies)


@needs_vmas
@pytest.mark.parametrize("name", ["vmas/navigation", "vmas/dispersion"])
def test_the_same_seed_gives_the_same_numbers_twice(name):
    """Two task objects, the same generators: the same episodes, observations, costs and metrics, bit for bit; a
    bucket shares no world with another (interleaving buckets changes nothing)."""
    from neurosym_cli.tasks import Rng

    def episode(task, interleave=False):
        gen = torch.Generator().manual_seed(7)
        buckets = task.reset(5, gen)
        other = task.reset(3, torch.Generator().manual_seed(8))[0] if interleave else None
        out = []
        for s in buckets:
            for t in range(4):
                obs = task.observe(s, Rng(gen))
                s = task.step(s, obs.agent[..., :2] - 0.3 * obs.rel[:, :, 0, :2])
                if other is not None:  # another bucket of the same task steps in between
                    other = task.step(other, torch.ones(other.batch, other.n_agents, 2))
                out += [obs.agent, obs.rel, task.cost(s, None), *task.metrics(s).values()]
        return out

    a, b, c = episode(_task(name)), episode(_task(name)), episode(_task(name), interleave=True)
    assert all(torch.equal(x, y) and torch.equal(x, z) for x, y, z in zip(a, b, c))
    seeder = lambda k: torch.Generator().manual_seed(100 + k)  # noqa: E731
    (e1, _), (e2, _) = _task(name).test_episodes(seeder), _task(name).test_episodes(seeder)
    assert all(torch.equal(x.pos, y.pos) and torch.equal(x.lm_pos, y.lm_pos) for x, y in zip(e1, e2))
    assert len({e.n_agents for e in e1}) == len(set(_cfg(name).test_sizes or _cfg(name).sizes))


@needs_vmas
def test_costs_and_metrics_by_hand():
    """navigation: goal distances plus the collision ramp; on_goal within the goal radius; collisions by radii."""
    import dataclasses

    task = _task()
    s = task.reset(1, torch.Generator().manual_seed(0))[0]
    n = s.n_agents
    goals = task.goal_pos(s)
    pos = goals.clone()
    pos[0, 1] = pos[0, 0] + torch.tensor([0.1, 0.0])  # agent 1 overlaps agent 0 (radii 0.1 each), off its goal
    s = dataclasses.replace(s, pos=pos)
    off = float((pos[0, 1] - goals[0, 1]).norm())
    ramp = 1.0 * (1 - 0.1 / (2 * 0.2))
    others = sum(max(0.0, 1 - float((pos[0, i] - pos[0, j]).norm()) / 0.4)
                 for i in range(n) for j in range(i + 1, n) if (i, j) != (0, 1))
    assert abs(float(task.cost(s, None)) - (off + ramp + others)) < 1e-4
    m = task.metrics(s)
    assert float(m["on_goal"]) == (n - 1) / n and float(m["success"]) == 0.0
    assert float(m["collisions"]) >= 1.0


@needs_vmas
def test_features_have_sources_and_read_the_observation():
    """Every feature is exportable (declares its source) and gd is the distance to the goal."""
    from neurosym_cli.tasks import Rng

    task = _task()
    fmap = task.features("v2")
    assert all(f.source is not None for f in fmap.vocab.features)
    s = task.reset(2, torch.Generator().manual_seed(0))[0]
    obs = task.observe(s, Rng(torch.Generator().manual_seed(1)))
    view = fmap.view(obs.agent, obs.rel)
    assert torch.allclose(view["gd"][..., 0], (task.goal_pos(s) - s.pos).norm(dim=-1))


# ----------------------------------------------------------------------------------------------- bad input
def test_without_vmas_a_vmas_task_is_one_line_naming_the_extra(monkeypatch):
    from neurosym_cli.errors import ConfigError
    from neurosym_cli.tasks.vmas import VmasConfig, VmasTask

    monkeypatch.setitem(sys.modules, "vmas", None)  # import vmas raises ImportError
    with pytest.raises(ConfigError, match=r"vmas extra: pip install -e '\.\[vmas\]'"):
        VmasTask(VmasConfig())


@needs_vmas
def test_bad_scenarios_are_one_line():
    """An unknown name lists the available ones; a scenario without what the features or the cost need names it; a
    reward that keeps state between calls (navigation's pos_shaping) is refused for cost=reward."""
    from neurosym_cli.errors import ConfigError
    from neurosym_cli.tasks.vmas import VmasConfig, VmasTask

    with pytest.raises(ConfigError, match=r"unknown VMAS scenario 'navigaton'; choose one of: .*navigation"):
        VmasTask(VmasConfig(scenario="navigaton"))
    with pytest.raises(ConfigError, match=r"'dispersion' lacks agents with a `goal` landmark, which task.vectors "
                                          r"'goal' needs \(features gx gy gd gtheta\)"):
        VmasTask(VmasConfig(scenario="dispersion", cost="coverage", vectors=["goal"]))
    with pytest.raises(ConfigError, match="reward\\(\\) keeps state between calls"):
        VmasTask(VmasConfig(cost="reward"))
    with pytest.raises(ConfigError, match="observation width depends on N"):
        VmasTask(VmasConfig(scenario="dispersion", cost="coverage", vectors=["nearest_landmark"], team_sizes=[3, 4]))
    with pytest.raises(ConfigError, match="task.cost must be one of"):
        VmasConfig(cost="fun")


@needs_vmas
def test_unknown_scenario_on_the_command_line_is_one_line(tmp_path):
    p = run(["train", "task=vmas/navigation", "task.scenario=navigaton", *COMMON], tmp_path, check=False)
    line = one_line(p)
    assert "unknown VMAS scenario 'navigaton'" in line and "dispersion" in line


USER_SCENARIO = '''
"""A BaseScenario of one's own: agents reach their own goals; the reward reads only the world (stateless)."""
import torch
from vmas.simulator.core import Agent, Landmark, Sphere, World
from vmas.simulator.scenario import BaseScenario


class Reach(BaseScenario):
    def make_world(self, batch_dim, device, n_agents=3, **kwargs):
        world = World(batch_dim, device)
        for i in range(n_agents):
            agent = Agent(name=f"agent_{i}", collide=False, shape=Sphere(0.05))
            world.add_agent(agent)
            agent.goal = Landmark(name=f"goal_{i}", collide=False)
            world.add_landmark(agent.goal)
        return world

    def reset_world_at(self, env_index=None):
        for e in self.world.agents + self.world.landmarks:
            e.set_pos(torch.rand(self.world.batch_dim, 2, device=self.world.device) * 2 - 1, batch_index=env_index)

    def observation(self, agent):
        return torch.cat([agent.state.pos, agent.state.vel, agent.goal.state.pos - agent.state.pos], -1)

    def reward(self, agent):
        return -torch.linalg.vector_norm(agent.state.pos - agent.goal.state.pos, dim=-1)


class Frozen(Reach):
    """Detaches the actions: no gradient reaches the physics."""

    def process_action(self, agent):
        agent.action.u = agent.action.u.detach()
'''


def _user_dir(tmp_path):
    (tmp_path / "myscen.py").write_text(USER_SCENARIO)
    conf = tmp_path / "conf" / "task"
    conf.mkdir(parents=True)
    (conf / "reach.yaml").write_text(textwrap.dedent("""\
        _target_: neurosym_cli.tasks.vmas.VmasTask
        name: reach
        scenario: myscen:Reach
        agents_per_group: 3
        horizon: 20
        eval_episodes: 2
        cost: reward
        vectors: [goal]
        """))
    return ["--config-dir", str(tmp_path / "conf")]


@needs_vmas
def test_a_non_differentiable_step_is_refused_before_training(tmp_path, monkeypatch):
    from neurosym_cli.errors import ConfigError
    from neurosym_cli.tasks.vmas import VmasConfig, VmasTask

    _user_dir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    VmasTask(VmasConfig(scenario="myscen:Reach", agents_per_group=3, cost="reward"))  # stateless reward: accepted
    with pytest.raises(ConfigError, match="passes no gradient from the actions"):
        VmasTask(VmasConfig(scenario="myscen:Frozen", agents_per_group=3))
    with pytest.raises(ConfigError, match="is not a vmas BaseScenario"):
        VmasTask(VmasConfig(scenario="myscen:torch"))


@needs_vmas
@pytest.mark.slow
def test_a_users_own_scenario_runs_train_synth_eval(tmp_path):
    """A BaseScenario subclass in a file outside the package, its YAML in the user's config directory, through
    train, synth and eval at the tiny budget, with the scenario's own reward as the cost; trained and evaluated
    again from the same seed in another runs root, it gives the same weights and the same costs."""
    cd = _user_dir(tmp_path)
    common = ["task=reach", *COMMON]
    run(["train", *cd, *common], tmp_path)
    run(["synth", *cd, *common], tmp_path)
    run(["eval", *cd, *common, "baseline=prog"], tmp_path)
    prog = run_dir("eval", tmp_path, *common, "baseline=prog", config_dir=cd[1])  # the task's lam and objective
    assert prog.label.startswith("prog-k2-lam0.25-v1-scaled")  # and the default search's suffix
    m = json.loads((prog.eval_dir() / "metrics.json").read_text())
    assert set(m["summary"]) >= {"cost", "collisions"} and m["summary"]["cost"]["mean"] > 0  # minus -distance
    # the same seed, the same numbers: training and evaluation again in another runs root, weights and costs equal
    again = tmp_path / "again"
    run(["train", *cd, *common, f"runs_root={again}"], tmp_path)
    for root in (tmp_path, again):
        run(["eval", *cd, *common, "baseline=tf-full", f"runs_root={root}"], tmp_path)
    w1, w2 = (torch.load(r / "reach/tiny/seed0/train/oracle/model.pt", weights_only=True)["state_dict"]
              for r in (tmp_path, again))
    assert w1.keys() == w2.keys() and all(torch.equal(w1[k], w2[k]) for k in w1)
    e1, e2 = (json.loads((r / "reach/tiny/seed0/eval/tf-full/metrics.json").read_text())["per_seed"]
              for r in (tmp_path, again))
    assert [s["cost"] for s in e1] == [s["cost"] for s in e2] and len(e1) == 2


@needs_vmas
@pytest.mark.slow
def test_the_pipeline_on_vmas_navigation_end_to_end(tmp_path):
    """The paper's method (PAPER_METHOD): the VMAS adapter is tested, and prog runs under the searched program (its
    label k2-lam0.25-v1-scaled), not the front's pick, whose retrainings would take most of the time."""
    p = run(["pipeline", "task=vmas/navigation", *COMMON, "baselines=[tf-full,hard-attn,dist,prog,no-comm]",
             *PAPER_METHOD], tmp_path, timeout=900)
    root = tmp_path / "vmas-navigation/tiny/seed0"
    assert (root / "synth/k2-lam0.25-v1-scaled/program.txt").exists()
    for b in ("tf-full", "hard-attn-k2", "dist-k2", "prog-k2-lam0.25-v1-scaled", "no-comm"):
        m = json.loads((root / f"eval/{b}/metrics.json").read_text())
        assert {"cost", "on_goal", "success", "collisions"} <= set(m["summary"]), b
    assert p.returncode == 0
