"""The VMAS task: its schema (:class:`VmasConfig`) and the task protocol over one VMAS instance per bucket shape
(:class:`VmasTask`); the state/world bridge is in world.py, the costs in objectives.py (docs/vmas.md)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ...config import TaskConfig
from ...errors import ConfigError, check
from ...utils.lazy import LazyModule
from ..base import Observation, Rng, Scene, clip_speed, pairwise_distances, safe_norm
from ..features import Columns, FeatureMap, column_feature, vector_map
from . import world as bridge
from .objectives import OBJECTIVES, VECTORS
from .scenarios import make_env
from .world import VmasState, World

if TYPE_CHECKING:
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")


# --------------------------------------------------------------------------------------------- the schema
@dataclass
class VmasConfig(TaskConfig):
    """A VMAS scenario trained through its differentiable physics (docs/vmas.md)."""

    _target_: str = "neurosym_cli.tasks.vmas.VmasTask"
    name: str = "vmas-navigation"
    scenario: str = "navigation"
    """a VMAS scenario name (vmas/scenarios/<name>.py) or module:Class, your own BaseScenario subclass"""
    scenario_kwargs: dict[str, Any] = field(default_factory=dict)
    """keyword arguments of the scenario's make_world (e.g. n_lidar_rays, collisions); N is passed as size_kwarg"""
    size_kwarg: str = "n_agents"
    """the make_world keyword that sets the number of agents"""
    agents_per_group: int = 4
    """N when team_sizes is empty; what `neurosym stress` varies"""
    team_sizes: list[int] = field(default_factory=list)
    """training team sizes, one VMAS instance per size (episodes drawn uniformly); empty = [agents_per_group]"""
    test_sizes: list[int] = field(default_factory=list)
    """evaluation team sizes, episode k of a seed has test_sizes[k % len]; empty = the training sizes"""
    horizon: int = 50
    eval_episodes: int = 6
    cost: str = "goal_distance"
    """the objective (OBJECTIVES): goal_distance, coverage or reward (the scenario's negated reward)"""
    vectors: list[str] = field(default_factory=lambda: ["goal"])
    """2-D vectors of the agent observation and its features (VECTORS): goal, nearest_landmark, position"""
    scenario_obs: bool = True
    """append the scenario's own observation(agent) to s_i (its width must not depend on N across team_sizes)"""
    spawn_half_width: float = 0.0
    """world units: > 0 re-spawns agents uniformly in [-w, w]^2 after VMAS's reset (dispersion starts every agent
    at the origin, where no rule can tell them apart); 0 keeps VMAS's spawn"""
    noise_std: float = 0.02
    """world units: noise on the observed offsets x_j - x_i"""
    vel_noise_std: float = 0.02
    """world units/s: noise on the observed relative velocities v_j - v_i"""
    collision_weight: float = 0.0
    """shaping 'collision ramp': weight of w max(0, 1 - d / (2 (r_i + r_j))) per agent pair (VMAS's collision
    penalty is a step function with zero gradient)"""

    def __post_init__(self) -> None:
        super().__post_init__()
        sizes = self.team_sizes or [self.agents_per_group]
        check(all(n >= 2 for n in sizes + list(self.test_sizes)), "task.team_sizes/test_sizes need at least 2 agents")
        check(self.cost in OBJECTIVES, f"task.cost must be one of {', '.join(OBJECTIVES)}, got {self.cost!r}")
        bad = [v for v in self.vectors if v not in VECTORS]
        check(not bad, f"task.vectors: unknown {', '.join(bad)}; choose from {', '.join(VECTORS)}")
        check(self.noise_std >= 0 and self.vel_noise_std >= 0, "task.noise_std and vel_noise_std must be >= 0")
        check(self.size_kwarg not in self.scenario_kwargs,
              f"task.scenario_kwargs.{self.size_kwarg} would be replaced: neurosym passes the team size as "
              f"{self.size_kwarg} from task.agents_per_group (or task.team_sizes); set "
              f"task.agents_per_group={self.scenario_kwargs.get(self.size_kwarg)!s} instead")

    @property
    def sizes(self) -> list[int]:
        return list(self.team_sizes or [self.agents_per_group])

    @property
    def max_agents(self) -> int:
        return max(self.sizes + list(self.test_sizes))


# ------------------------------------------------------------------------------------------------ the task
class VmasTask:
    """s_i = [the configured vectors (2 each), v_i, scenario.observation(agent_i)]; o_ij = [x_j - x_i + noise,
    v_j - v_i + noise] (Dp = 4); action = the force, rescaled to norm at most VMAS's u_range."""

    Config = VmasConfig
    pair_dim = 4
    action_dim = 2

    def __init__(self, cfg: VmasConfig, horizon: int | None = None):
        self.cfg = cfg
        self.horizon = horizon or cfg.horizon
        self.rounds = cfg.rounds
        self._envs: dict[tuple[int, int, str], Any] = {}
        self._goals: dict[int, list[int]] = {}
        self.world = self._inspect()
        self.obs_dim = 2 * len(cfg.vectors) + 2 + self.world.obs_width

    def __getstate__(self) -> dict:  # VMAS environments stay in their process; a copy rebuilds its own
        return {**self.__dict__, "_envs": {}, "_goals": {}}

    # ------------------------------------------------------------------------------ VMAS instances
    def _env(self, n: int, b: int, device: Any) -> Any:
        """The VMAS environment of team size n and batch b (one per bucket shape, built once)."""
        key = (n, b, str(device))
        if key not in self._envs:
            c = self.cfg
            self._envs[key] = make_env(c.scenario, n, b, device, c.size_kwarg, c.scenario_kwargs)
        return self._envs[key]

    def _inspect(self) -> World:
        """Build the first team size once: read what the adapter needs, refuse in one line what it cannot use."""
        c = self.cfg
        sizes = sorted(set(c.sizes + list(c.test_sizes)))
        env = self._env(sizes[0], 1, "cpu")
        w = env.world
        agents, lms = w.agents, w.landmarks
        goals = [getattr(a, "goal", None) for a in agents]
        goal = tuple(next(k for k, lm in enumerate(lms) if lm is g) if any(lm is g for lm in lms) else -1
                     for g in goals)
        goal_ok = all(k >= 0 for k in goal)
        for name in list(c.vectors) + [OBJECTIVES[c.cost].needs]:
            vec = VECTORS.get(name)
            if name == "goal" and not goal_ok or name == "nearest_landmark" and not lms:
                what = f"task.vectors '{name}'" if name in c.vectors else f"task.cost={c.cost}"
                raise ConfigError(f"scenario {c.scenario!r} lacks {vec.needs}, which {what} needs "
                                  f"(features {vec.prefix}x {vec.prefix}y {vec.prefix}d {vec.prefix}theta)")
        width = 0
        if c.scenario_obs:
            widths = {n: int(self._env(n, 1, "cpu").scenario.observation(self._env(n, 1, "cpu").world.agents[0])
                             .shape[-1]) for n in sizes}
            if len(set(widths.values())) > 1:
                raise ConfigError(f"scenario {c.scenario!r}: its observation width depends on N "
                                  f"({', '.join(f'N={n}: {k}' for n, k in widths.items())}); use one team size "
                                  f"or task.scenario_obs=false")
            width = widths[sizes[0]]
        u = agents[0].u_range
        world = World(len(lms), tuple(float(a.shape.radius) for a in agents),
                      tuple(float(getattr(lm.shape, "radius", 0.0)) for lm in lms),
                      float(u if not isinstance(u, (list, tuple)) else min(u)), goal if goal_ok else None, width)
        self.world = world
        self._check_step(env)
        return world

    def _check_step(self, env: Any) -> None:
        """Refuse a scenario whose step does not pass gradients from the action to the positions, or (cost=reward)
        whose reward keeps state between calls, before any training."""
        s = bridge.read(bridge.reset(env, 0))
        a = torch.full((1, s.n_agents, 2), 0.1 * self.world.u_range, requires_grad=True)
        nxt = bridge.physics(env, s, a)
        g = torch.autograd.grad(nxt.pos.sum(), a, allow_unused=True)[0] if nxt.pos.requires_grad else None
        if g is None or not torch.isfinite(g).all() or g.abs().sum() == 0:
            raise ConfigError(f"scenario {self.cfg.scenario!r}: its step passes no gradient from the actions to the "
                              f"positions (non-differentiable dynamics); BPTT cannot train through it")
        if self.cfg.cost == "reward":
            r1, r2 = bridge.rewards(env), bridge.rewards(env)
            if not torch.allclose(r1, r2):
                raise ConfigError(f"scenario {self.cfg.scenario!r}: reward() keeps state between calls (two calls "
                                  f"on one world differ), so it is not a function of the state; use task.cost="
                                  f"goal_distance or coverage, or make reward() read only the world")

    # ------------------------------------------------------------------------------ the protocol
    def reset(self, batch: int, gen: torch.Generator) -> list[VmasState]:
        """``batch`` episodes split evenly over team_sizes, one bucket per size. Even, not drawn: a bucket's shape
        (N, B) is then the same at every training step, so each VMAS instance is built once."""
        sizes = self.cfg.sizes
        counts = [batch // len(sizes) + (k < batch % len(sizes)) for k in range(len(sizes))]
        return [self._reset_bucket(n, b, gen) for n, b in zip(sizes, counts) if b]

    def _reset_bucket(self, n: int, b: int, gen: torch.Generator) -> VmasState:
        seed = int(torch.randint(0, 2**31 - 1, (1,), generator=gen))
        s = bridge.read(bridge.reset(self._env(n, b, "cpu"), seed))
        if self.cfg.spawn_half_width > 0:
            w = self.cfg.spawn_half_width
            s = dataclasses.replace(s, pos=(torch.rand(b, n, 2, generator=gen) * 2 - 1) * w)
        return s

    def test_episodes(self, seeder):
        """``eval_episodes`` episodes per evaluation seed, episode k with test_sizes[k % len] agents and its own
        generator (its VMAS seed and later its noise)."""
        sizes = list(self.cfg.test_sizes) or self.cfg.sizes
        gens = [seeder(k) for k in range(self.cfg.eval_episodes)]
        return [self._reset_bucket(sizes[k % len(sizes)], 1, g) for k, g in enumerate(gens)], gens

    def observe(self, state: VmasState, rng: Rng) -> Observation:
        b, n = state.batch, state.n_agents
        parts = [VECTORS[v].fn(self, state) for v in self.cfg.vectors] + [state.vel]
        if self.world.obs_width:
            parts.append(bridge.observations(self._env(n, b, state.pos.device), state))
        off = state.pos[:, None, :, :] - state.pos[:, :, None, :]  # [i, j] = x_j - x_i
        dvel = state.vel[:, None, :, :] - state.vel[:, :, None, :]
        if self.cfg.noise_std > 0:
            off = off + self.cfg.noise_std * rng.randn(b, n, n, 2)
        if self.cfg.vel_noise_std > 0:
            dvel = dvel + self.cfg.vel_noise_std * rng.randn(b, n, n, 2)
        return Observation(agent=torch.cat(parts, -1), rel=torch.cat([off, dvel], -1))

    def target(self, action: Tensor) -> Tensor:
        """The force as it acts: rescaled to norm at most u_range (keeps the direction and the gradient, where
        VMAS's clamp would zero it), so each component lies within VMAS's bounds."""
        return clip_speed(action, self.world.u_range * (1 - 1e-4))

    def step(self, state: VmasState, action: Tensor) -> VmasState:
        env = self._env(state.n_agents, state.batch, state.pos.device)
        nxt = bridge.physics(env, state, self.target(action))
        if self.cfg.cost == "reward":
            nxt = dataclasses.replace(nxt, reward=bridge.rewards(env))
        return nxt

    def cost(self, next_state: VmasState, action: Tensor) -> Tensor:
        """(B,) the objective's cost plus the collision ramp (docs/vmas.md, 'Costs')."""
        c = OBJECTIVES[self.cfg.cost].cost(self, next_state)
        if self.cfg.collision_weight > 0:
            d = safe_norm(next_state.pos[:, :, None] - next_state.pos[:, None, :])
            r = self.radius(next_state)
            reach = 2 * (r[:, :, None] + r[:, None, :])
            upper = torch.ones(d.shape[-1], d.shape[-1], dtype=torch.bool, device=d.device).triu(1)
            c = c + self.cfg.collision_weight * (torch.relu(1 - d / reach) * upper).sum((1, 2))
        return c

    def metrics(self, state: VmasState) -> dict[str, Tensor]:
        """The objective's success measures and collisions: agent pairs closer than the sum of their radii."""
        d = torch.cdist(state.pos, state.pos)
        r = self.radius(state)
        upper = torch.ones_like(d[0], dtype=torch.bool).triu(1)
        hits = ((d < r[:, :, None] + r[:, None, :]) & upper).sum((1, 2)).to(d.dtype)
        return {**OBJECTIVES[self.cfg.cost].metrics(self, state), "collisions": hits}

    def features(self, version: str) -> FeatureMap:
        """The vectors of s_i (x, y, norm, angle each), the observation of j (dx dy d theta), vd (my speed) and dv
        (its speed relative to me), all with their sources (exportable)."""
        k = len(self.cfg.vectors)
        vecs = [(VECTORS[v].prefix, VECTORS[v].owner, Columns("agent", 2 * i)) for i, v in enumerate(self.cfg.vectors)]
        extra = [column_feature("vd", "self", "my speed", Columns("agent", 2 * k), "d", "world units/s"),
                 column_feature("dv", "other", "its speed relative to me", Columns("rel", 2), "d", "world units/s")]
        return vector_map(vecs, version, extra=extra)

    # ------------------------------------------------------------------ helpers of the objectives
    def goal_pos(self, s: VmasState) -> Tensor:
        """(B, N, 2) each agent's goal landmark."""
        return s.lm_pos[:, self._goal_index(s.n_agents)]

    def _goal_index(self, n: int) -> list[int]:
        """Landmark index of each agent's goal at team size n (read once per size from a world of that size)."""
        if n not in self._goals:
            w = self._env(n, 1, "cpu").world
            self._goals[n] = [next(k for k, lm in enumerate(w.landmarks) if lm is a.goal) for a in w.agents]
        return self._goals[n]

    def radius(self, s: VmasState) -> Tensor:
        """(1, N) agent radii (every VMAS scenario here gives its agents one radius)."""
        return torch.full((1, s.n_agents), self.world.radius[0], device=s.pos.device)

    def lm_radius(self, s: VmasState) -> Tensor:
        """(1, L) landmark radii."""
        r = self.world.lm_radius[0] if self.world.lm_radius else 0.0
        return torch.full((1, s.lm_pos.shape[1]), r, device=s.pos.device)

    def lm_radius_of_goals(self, s: VmasState) -> Tensor:
        return self.lm_radius(s)[:, :1].expand(1, s.n_agents)

    # ------------------------------------------------------------------------ optional capabilities
    def distances(self, state: VmasState) -> Tensor:
        return pairwise_distances(state.pos)

    def with_team_size(self, n: int) -> "VmasTask":
        return VmasTask(dataclasses.replace(self.cfg, agents_per_group=n, team_sizes=[n], test_sizes=[n]),
                        self.horizon)

    def scene(self, state: VmasState) -> Scene:
        n = state.n_agents
        if self.world.goal is not None:
            return Scene(goal=self.goal_pos(state)[0], group=torch.arange(n), labelled=True)
        return Scene(goal=state.lm_pos[0], group=torch.zeros(n, dtype=torch.long), labelled=False)
