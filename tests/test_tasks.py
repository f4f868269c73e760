"""Tasks: the protocol's contract over every registered task (the paper's four, the ring example, a toy defined
here with a 4-wide pair observation), and the paper tasks' shapes, determinism, hand-computed costs, the grid
constraint and gradients through the dynamics."""

import math

import pytest
import torch

from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.tasks.random_grid import GridConfig
from neurosym_cli.tasks.unlabeled_goals import UnlabeledConfig
from neurosym_cli.tasks import Rng, make_task
from neurosym_cli.tasks.formation import FormationState
from neurosym_cli.tasks.random_cross import RandomCrossTask
from neurosym_cli.tasks.unlabeled_goals import UnlabeledGoalsTask

CROSS = CrossConfig(name="random-cross", test_settings=["0", "1", "0-2", "0-1", "0-1-2", "0-1-2-3"])
GRID = GridConfig(name="random-grid", ell=14.0)
UNLAB = UnlabeledConfig(name="unlabeled-goals", horizon=100, rounds=2)


def test_cross_reset_buckets_by_agent_count(gen):
    env = make_task(CROSS)
    buckets = env.reset(64, gen)
    assert sum(b.batch for b in buckets) == 64
    ns = [b.n_agents for b in buckets]
    assert ns == sorted(set(ns)) and set(ns) <= {10, 20, 30, 40}
    for b in buckets:
        assert b.pos.shape == (b.batch, b.n_agents, 2) and b.goal.shape == b.pos.shape
        assert b.group.shape == (b.batch, b.n_agents)


def test_reset_is_deterministic_given_the_generator():
    env = make_task(CROSS)
    a = env.reset(16, torch.Generator().manual_seed(3))
    b = env.reset(16, torch.Generator().manual_seed(3))
    c = env.reset(16, torch.Generator().manual_seed(4))
    assert all(torch.equal(x.pos, y.pos) and torch.equal(x.goal, y.goal) for x, y in zip(a, b))
    assert not all(x.pos.shape == y.pos.shape and torch.equal(x.pos, y.pos) for x, y in zip(a, c))


def test_cross_boxes_and_separation(gen):
    env = make_task(CROSS)
    s = env.setting("0-1-2-3", gen)
    centres = {0: (-7, 0), 1: (0, -7), 2: (7, 0), 3: (0, 7)}
    for g, (cx, cy) in centres.items():
        pts = s.pos[0, s.group[0] == g]
        goals = s.goal[0, s.group[0] == g]
        assert pts.shape == (10, 2)
        assert (pts - torch.tensor([cx, cy])).abs().max() <= 1.25 + 1e-6
        assert (goals + torch.tensor([cx, cy])).abs().max() <= 1.25 + 1e-6  # goal box opposite the start box
        d = torch.cdist(pts, pts) + torch.eye(10) * 10
        assert d.min() >= 0.5 - 1e-6


def test_grid_goal_boxes_adjacent_and_distinct(gen):
    env = make_task(GRID)
    s = env.reset(500, gen)[0]
    l = 14.0
    starts = torch.tensor([[-l, 0.0], [l, 0.0], [0.0, 0.0]])
    centre = lambda x: torch.round(x.reshape(500, 3, 10, 2).mean(2) / l) * l  # (B, 3, 2) box centres
    goal_c = centre(s.goal)
    assert torch.equal(centre(s.pos), starts.expand(500, 3, 2))
    # adjacent: exactly one grid step away from the start box (Manhattan distance l)
    assert torch.allclose((goal_c - starts).abs().sum(-1), torch.full((500, 3), l))
    # distinct goal boxes
    for i, j in [(0, 1), (0, 2), (1, 2)]:
        assert ((goal_c[:, i] - goal_c[:, j]).abs().sum(-1) > 0).all()
    # every one of the 16 allowed combinations occurs
    combos = {tuple(map(float, g.flatten())) for g in goal_c}
    assert len(combos) == 16


def test_formation_cost_matches_hand_computation():
    cfg = CrossConfig(name="t", num_groups=2)
    env = RandomCrossTask(cfg)
    pos = torch.tensor([[[0.0, 0.0], [0.05, 0.0], [3.0, 0.0]]])
    goal = torch.tensor([[[1.0, 0.0], [0.05, 2.0], [3.0, 4.0]]])
    group = torch.tensor([[0, 0, 1]])
    s = FormationState(pos, goal, group)
    dist = 1.0 + 2.0 + 4.0
    within = max(0.0, 5 * (2 - 0.05 / 0.1))  # agents 0, 1: 7.5
    across = max(0.0, 25 * (2 - 3.0 / 2.0)) + max(0.0, 25 * (2 - 2.95 / 2.0))  # (0, 2) and (1, 2)
    got = env.cost(s, torch.zeros(1, 3, 2))
    assert got.shape == (1,)
    assert math.isclose(float(got), dist + within + across, rel_tol=1e-5)
    assert float(env.metrics(s)["collisions"]) == 1.0  # the pair (0, 1) is closer than d_c
    cfg_off = CrossConfig(name="t", num_groups=2, collision_inter_group_weight=0.0)
    assert math.isclose(float(RandomCrossTask(cfg_off).cost(s, torch.zeros(1, 3, 2))), dist + within, rel_tol=1e-5)


def test_speed_is_clipped_and_step_integrates():
    env = RandomCrossTask(CrossConfig(name="t"))
    s = FormationState(torch.zeros(1, 2, 2), torch.ones(1, 2, 2), torch.zeros(1, 2, dtype=torch.long))
    nxt = env.step(s, torch.tensor([[[30.0, 40.0], [0.5, 0.0]]]))
    assert torch.allclose(nxt.pos[0, 0], torch.tensor([0.12, 0.16]), atol=1e-5)  # speed 50 -> 2, times dt 0.1
    assert torch.allclose(nxt.pos[0, 1], torch.tensor([0.05, 0.0]), atol=1e-5)


def test_observation_is_relative_and_noisy(gen):
    env = make_task(CROSS)
    s = env.setting("0", gen)
    clean = make_task(CrossConfig(name="c", noise_std=0.0)).observe(s, Rng(gen))
    assert torch.allclose(clean.rel[0, 2, 5], s.pos[0, 5] - s.pos[0, 2])  # o_ij = x_j - x_i
    assert torch.allclose(clean.agent, s.pos - s.goal)
    noisy = env.observe(s, Rng(gen))
    err = noisy.rel - clean.rel
    assert 0.03 < float(err.std()) < 0.07


def test_gradients_flow_through_the_dynamics(gen):
    env = make_task(CROSS)
    s = env.setting("0-2", gen)
    actions = torch.zeros(5, 1, 20, 2, requires_grad=True)
    total = 0.0
    for t in range(5):
        s = env.step(s, actions[t])
        total = total + env.cost(s, actions[t]).sum()
    total.backward()
    g = actions.grad
    assert torch.isfinite(g).all()
    assert (g[0].abs().sum() > 0) and (g[-1].abs().sum() > 0)
    # an early action influences every later cost: its gradient is larger than the last action's
    assert g[0].abs().sum() > g[-1].abs().sum()


def test_unlabeled_shapes_cost_and_ordering(gen):
    env = UnlabeledGoalsTask(UNLAB)
    s = env.reset(3, gen)[0]
    assert s.pos.shape == (3, 10, 2) and s.goal.shape == (3, 10, 2) and s.goal_order.shape == (3, 10, 10)
    obs = env.observe(s, Rng(gen))
    assert obs.agent.shape == (3, 10, 22) and obs.rel.shape == (3, 10, 10, 2)
    # the first goal offset is the nearest goal
    off = obs.agent[..., 2:].reshape(3, 10, 10, 2).norm(dim=-1)
    assert torch.all(off[..., 0] <= off.min(-1).values + 1e-6)
    # every agent puts all weight on its own nearest goal: uncovered = N - number of distinct nearest goals
    logits = torch.full((3, 10, 10), -30.0)
    logits[..., 0] = 30.0
    nearest = s.goal_order[..., 0]
    expected = torch.tensor([10 - len(set(n.tolist())) for n in nearest], dtype=torch.float32)
    assert torch.allclose(env.cost(s, logits), expected, atol=1e-4)
    # and it moves towards that goal
    nxt = env.step(s, logits)
    g = torch.gather(s.goal, 1, nearest[..., None].expand(-1, -1, 2))
    assert ((nxt.pos - g).norm(dim=-1) < (s.pos - g).norm(dim=-1)).all()


@pytest.mark.parametrize("bad", ["0-7", "x", ""])
def test_bad_cross_setting_is_a_config_error(bad, gen):
    from neurosym_cli.config import ConfigError

    with pytest.raises(ConfigError):
        make_task(CROSS).setting(bad, gen)


# ------------------------------------------------------------------------------------ the protocol's contract
import dataclasses  # noqa: E402
import sys  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402

from neurosym_cli.config import TaskConfig  # noqa: E402
from neurosym_cli.dsl.vocabulary import Feature  # noqa: E402
from neurosym_cli.tasks import Observation, TaskState, custom_map, probe, task_class  # noqa: E402
from neurosym_cli.tasks.base import concat_states, split_buckets  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


@dataclass
class ToyConfig(TaskConfig):
    """A toy: agents on a line pulled to the origin; o_ij carries offset, relative velocity and a 'same sign' bit."""

    _target_: str = "test_tasks.ToyTask"
    name: str = "toy"
    agents_per_group: int = 5
    horizon: int = 6
    gain: float = 0.5


@dataclass(frozen=True)
class ToyState(TaskState):
    vel: torch.Tensor  # (B, N, 2)
    heading: torch.Tensor  # (B, N) a field no paper task has


class ToyTask:
    Config = ToyConfig
    obs_dim, pair_dim, action_dim = 3, 4, 2

    def __init__(self, cfg, horizon=None):
        self.cfg, self.horizon, self.rounds = cfg, horizon or cfg.horizon, cfg.rounds

    def reset(self, batch, gen):
        n = self.cfg.agents_per_group
        pos = torch.randn(batch, n, 2, generator=gen)
        return [ToyState(pos, torch.zeros_like(pos), torch.zeros(batch, n))]

    def test_episodes(self, seeder):
        gens = [seeder(k) for k in range(2)]
        return [self.reset(1, g)[0] for g in gens], gens

    def observe(self, s, rng):
        off = s.pos[:, None] - s.pos[:, :, None]
        dv = s.vel[:, None] - s.vel[:, :, None]
        return Observation(torch.cat([s.pos, s.heading[..., None]], -1), torch.cat([off, dv], -1))

    def step(self, s, action):
        return dataclasses.replace(s, pos=s.pos + 0.1 * action, vel=action, heading=s.heading + 1)

    def cost(self, s, action):
        return self.cfg.gain * s.pos.norm(dim=-1).sum(-1)

    def target(self, action):
        return action

    def metrics(self, s):
        return {"spread": s.pos.std(1).sum(-1)}

    def features(self, version):
        return custom_map([(Feature("d", "other", "its distance", "m", (0.0, float("inf")), distance=True),
                            lambda v: v.rel[..., :2].norm(dim=-1)),
                           (Feature("dv", "other", "its relative speed", "m/s", (0.0, float("inf"))),
                            lambda v: v.rel[..., 2:].norm(dim=-1)),
                           (Feature("h", "self", "my heading", "steps"), lambda v: v.agent[..., 2:3])], version)


def _paper(name):
    from neurosym_cli.commands.apps import compose_config

    return compose_config("train", [f"task={name}"]).task


def _sparse_swarm():
    """The swarm task on its sparse path (pair source, cell lists) at a size the contract can afford."""
    import dataclasses

    return dataclasses.replace(_paper("swarm"), agents_per_group=7, sparse_from=0)


def _ring():
    sys.path.insert(0, str(ROOT / "examples" / "ring"))
    import ring  # noqa: F401  (the example, imported as neurosym imports it: from beside its config directory)

    return ring.RingConfig()


def _consensus():
    sys.path.insert(0, str(ROOT / "examples" / "consensus"))
    import consensus  # noqa: F401  (the example where communication matters, imported like the ring)

    return consensus.ConsensusConfig()


def _vmas(name):
    pytest.importorskip("vmas", reason="the vmas extra is not installed (pip install -e '.[vmas]')")
    return _paper(name)


TASKS = {"random-cross": lambda: _paper("random-cross"), "random-grid": lambda: _paper("random-grid"),
         "unlabeled-goals": lambda: _paper("unlabeled-goals"), "two-groups-cross": lambda: _paper("two-groups-cross"),
         "swarm": lambda: _paper("swarm"), "swarm-sparse": lambda: _sparse_swarm(),
         "ring": _ring, "consensus": _consensus, "toy": lambda: ToyConfig(),
         "vmas/navigation": lambda: _vmas("vmas/navigation"), "vmas/dispersion": lambda: _vmas("vmas/dispersion"),
         "vmas/navigation-nolidar": lambda: _vmas("vmas/navigation-nolidar"),
         "vmas/navigation-avoid": lambda: _vmas("vmas/navigation-avoid")}


def test_the_contract_covers_every_task_yaml():
    """Every task YAML of the package (nested ones as Hydra names them: vmas/navigation) and of the examples is in
    the contract test below."""
    root = ROOT / "conf" / "task"
    names = {p.relative_to(root).with_suffix("").as_posix() for p in root.rglob("*.yaml")} - {"random-grid-noisy"}
    names |= {p.stem for p in (ROOT / "examples").glob("*/conf/task/*.yaml")}
    assert names <= set(TASKS), sorted(names - set(TASKS))


@pytest.mark.parametrize("name", list(TASKS))
def test_task_contract(name):
    """Shapes of every method, the features against the DSL's declaration, gradients from the cost back to the
    actions through the dynamics, and bucket operations that keep every state field."""
    cfg = TASKS[name]()
    task = make_task(cfg, 4)
    assert task_class(cfg._target_) is type(task)
    probe(task, name)
    gen = torch.Generator().manual_seed(0)
    buckets = task.reset(6, gen)
    assert sum(b.batch for b in buckets) == 6
    s = buckets[0]
    b, n = s.batch, s.n_agents
    obs = task.observe(s, Rng(gen))
    assert obs.agent.shape == (b, n, task.obs_dim) and obs.rel.shape == (b, n, n, task.pair_dim)
    # gradients: the summed cost of a few steps reaches every action
    actions = torch.zeros(3, b, n, task.action_dim, requires_grad=True)
    total, st = 0.0, s
    for t in range(3):
        st = task.step(st, actions[t])
        c = task.cost(st, actions[t])
        assert c.shape == (b,)
        total = total + c.sum()
    total.backward()
    assert torch.isfinite(actions.grad).all() and actions.grad[0].abs().sum() > 0
    assert task.target(torch.zeros(b, n, task.action_dim)).shape[:2] == (b, n)
    for k, v in task.metrics(st).items():
        assert v.shape == (b,), k
    # the feature map: every declared feature computes, with the shape of its subject
    for version in ("v1", "v2"):
        fmap = task.features(version)
        view = fmap.view(obs.agent, obs.rel)
        for f in fmap.vocab.features:
            want = (b, n, 1) if f.of == "self" else (b, n, n)
            assert tuple(view[f.name].shape) == want, (f.name, view[f.name].shape)
            lo, hi = f.bounds
            assert (view[f.name] >= lo - 1e-6).all() and (view[f.name] <= hi + 1e-6).all(), f.name
        pair, agent, fp, fa = view.stacked()
        assert fp.shape == (len(pair), b * n * n) and fa.shape == (len(agent), b * n)
    # bucket operations keep every field of the task's state class
    moved = [s.take(slice(0, 1)), s.detach(), s.to(torch.device("cpu")), concat_states([s, s]),
             split_buckets([s], 2)[0]]
    for m in moved:
        assert type(m) is type(s)
        for f in dataclasses.fields(s):
            v = getattr(s, f.name)
            if isinstance(v, torch.Tensor):
                assert getattr(m, f.name).shape[1:] == v.shape[1:], f.name
    assert concat_states([s, s]).batch == 2 * b
    episodes, gens = task.test_episodes(lambda k: torch.Generator().manual_seed(k))
    assert len(episodes) == len(gens) and all(e.batch == 1 for e in episodes)


def test_a_class_without_the_protocol_is_one_line():
    from neurosym_cli.errors import ConfigError

    with pytest.raises(ConfigError, match=r"lacks .*step\(\)"):
        task_class("test_tasks.ToyConfig")  # a dataclass, not a task
    with pytest.raises(ConfigError, match="cannot import 'no_such_module'"):
        task_class("no_such_module.Task")


def test_a_wrong_observation_width_is_one_line_before_training():
    from neurosym_cli.errors import ConfigError

    class Wide(ToyTask):
        pair_dim = 2  # declares 2, observes 4

    with pytest.raises(ConfigError, match=r"observe\(\) gives rel of shape \(2, 5, 5, 4\)"):
        probe(Wide(ToyConfig()), "wide")
