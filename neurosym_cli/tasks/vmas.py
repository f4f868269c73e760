"""VMAS scenarios as neurosym tasks: BPTT through VMAS's differentiable physics (``make_env(grad_enabled=True)``).

VMAS (proroklab/VectorizedMultiAgentSimulator, GPLv3, the optional extra ``pip install -e '.[vmas]'``) keeps its
state in a mutable ``World``; neurosym's tasks are pure functions of a :class:`TaskState`. The adapter is the
functional contract between the two (docs/vmas.md, 'The functional contract'):

- every physical quantity of the world (pos, vel, rot, ang_vel of every agent and landmark) is a field of
  :class:`VmasState`, episode axis first. ``step`` writes the state into the world (copies: ``clone`` keeps the
  graph and keeps VMAS's in-place updates off the state's tensors), runs VMAS's own action pipeline and physics
  (``Environment._set_action``, ``process_action``, ``pre_step``, ``World.step``, ``post_step``) and reads the
  world back into a new state: the graph runs from the old state's tensors and the action through VMAS's
  integrator to the new ones, and nothing of one step survives in the world that the next step reads;
- one VMAS ``Environment`` per (team size N, batch B, device), built lazily and cached: a bucket's episodes
  never share a world with another bucket's;
- reset draws a seed from the task's generator and resets through VMAS (``Environment.reset(seed=...)``, which
  seeds VMAS's private RNG state, not the global one), so an episode is a function of its generator.

What the adapter does not carry is a scenario's private attributes (navigation's ``pos_shaping``, dispersion's
``eaten``): costs and metrics are computed from the state here (:data:`OBJECTIVES`), never from VMAS's stateful
``reward``, except ``cost=reward``, which is accepted only when ``reward`` is a function of the world (checked).
"""

from __future__ import annotations

import dataclasses
import importlib
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable

from ..config import TaskConfig
from ..errors import ConfigError, check
from ..utils.lazy import LazyModule
from .base import Observation, Rng, Scene, TaskState, clip_speed, pairwise_distances, safe_norm
from .features import Columns, FeatureMap, column_feature, vector_map

if TYPE_CHECKING:
    import torch
    from torch import Tensor
else:
    torch = LazyModule("torch")

EXTRA = "pip install -e '.[vmas]' in the neurosym checkout (or pip install 'vmas>=1.5'; GPLv3)"


def _vmas() -> Any:
    """The vmas package, or the one-line error naming the extra."""
    try:
        import vmas
    except ImportError:
        raise ConfigError(f"VMAS tasks need the vmas extra: {EXTRA}") from None
    return vmas


def builtin_scenarios() -> list[str]:
    """Names of the scenarios shipped with VMAS (its own lists: scenarios, mpe_scenarios, debug_scenarios)."""
    vmas = _vmas()
    return sorted({*vmas.scenarios, *getattr(vmas, "mpe_scenarios", ()), *getattr(vmas, "debug_scenarios", ())})


def scenario_of(spec: str) -> Any:
    """A fresh BaseScenario for ``spec``: a VMAS scenario name (``navigation``) or ``module:Class`` (a user's
    BaseScenario subclass). Unknown names are one line with the available ones."""
    _vmas()
    from vmas.simulator.scenario import BaseScenario

    if ":" in spec:
        from .registry import import_target

        cls = import_target(spec)
        if not (isinstance(cls, type) and issubclass(cls, BaseScenario)):
            raise ConfigError(f"task.scenario={spec!r} is not a vmas BaseScenario subclass")
        return cls()
    names = builtin_scenarios()
    if spec not in names:
        raise ConfigError(f"unknown VMAS scenario {spec!r}; choose one of: {', '.join(names)} "
                          f"(or task.scenario=module:Class for your own BaseScenario)")
    return importlib.import_module("vmas.scenarios").load(f"{spec}.py").Scenario()


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

    @property
    def sizes(self) -> list[int]:
        return list(self.team_sizes or [self.agents_per_group])

    @property
    def max_agents(self) -> int:
        return max(self.sizes + list(self.test_sizes))


@dataclass(frozen=True)
class VmasState(TaskState):
    """Every physical quantity of a VMAS world, episode axis first: pos (B, N, 2) from TaskState, plus:"""

    vel: Tensor  # (B, N, 2) agent velocities, world units/s
    rot: Tensor  # (B, N, 1) agent headings, rad
    ang_vel: Tensor  # (B, N, 1) rad/s
    lm_pos: Tensor  # (B, L, 2) landmark positions (navigation: the goals; dispersion: the food)
    lm_vel: Tensor  # (B, L, 2)
    lm_rot: Tensor  # (B, L, 1)
    lm_ang_vel: Tensor  # (B, L, 1)
    reward: Tensor  # (B, N) VMAS's reward of the last step (cost=reward only; zeros otherwise)


@dataclass(frozen=True)
class World:
    """What the adapter reads once from a built scenario: landmark count, radii, action range, goal indices."""

    n_landmarks: int
    radius: tuple[float, ...]  # per agent, world units
    lm_radius: tuple[float, ...]  # per landmark
    u_range: float  # bound of each action component (force)
    goal: tuple[int, ...] | None  # landmark index of each agent's `goal`, None when agents have none
    obs_width: int  # width of scenario.observation(agent), 0 with scenario_obs off


# ------------------------------------------------------------------------------ vectors and objectives
@dataclass(frozen=True)
class Vector:
    """A 2-D vector of the asking agent, computed from the state: its feature prefix, words, and what it needs."""

    prefix: str
    owner: str  # the phrase of its features' words ("my goal" -> "my distance to my goal")
    fn: Callable[["VmasTask", VmasState], "Tensor"]  # -> (B, N, 2)
    needs: str = ""  # what the scenario must have (the one-line refusal quotes it)


def _nearest_landmark(task: "VmasTask", s: VmasState) -> Tensor:
    off = s.lm_pos[:, None, :, :] - s.pos[:, :, None, :]  # (B, N, L, 2)
    k = off.norm(dim=-1).argmin(-1)  # (B, N)
    return torch.gather(off, 2, k[..., None, None].expand(-1, -1, 1, 2)).squeeze(2)


VECTORS: dict[str, Vector] = {
    "goal": Vector("g", "my goal", lambda t, s: t.goal_pos(s) - s.pos, "agents with a `goal` landmark"),
    "nearest_landmark": Vector("l", "the nearest landmark", _nearest_landmark, "at least one landmark"),
    "position": Vector("p", "position", lambda t, s: s.pos),
}
"""task.vectors -> the vector: s_i starts with these (2 columns each), then the velocity, then the scenario's own"""


@dataclass(frozen=True)
class Objective:
    """A differentiable per-step cost (B,) and the success metrics of the scenarios it belongs to."""

    cost: Callable[["VmasTask", VmasState], "Tensor"]
    metrics: Callable[["VmasTask", VmasState], dict[str, "Tensor"]]
    needs: str = ""  # a VECTORS key the objective reads (goal), checked like the vectors


def _goal_distance(t: "VmasTask", s: VmasState) -> Tensor:
    """navigation: sum_i |x_i - g_i|. VMAS's reward is the potential difference d_{t-1} - d_t (shared); its negated
    sum over an episode telescopes to d_T - d_0 and rewards only the end; the potential itself, summed over the
    horizon, is the same return accumulated at every step (plus a constant) and rewards arriving early."""
    return safe_norm(s.pos - t.goal_pos(s)).sum(-1)


def _on_goal(t: "VmasTask", s: VmasState) -> dict[str, Tensor]:
    """on_goal: fraction of agents within their goal's radius (VMAS's on_goal); success: all of them (VMAS's done)."""
    on = (s.pos - t.goal_pos(s)).norm(dim=-1) < t.lm_radius_of_goals(s)
    return {"on_goal": on.float().mean(-1), "success": on.all(-1).float()}


def _coverage(t: "VmasTask", s: VmasState) -> Tensor:
    """dispersion: sum over food of the distance to its nearest agent. VMAS's reward is an indicator (eating) with
    zero gradient; this potential is zero exactly when every food item has an agent on it."""
    return safe_norm(s.lm_pos[:, :, None, :] - s.pos[:, None, :, :]).min(-1).values.sum(-1)


def _covered(t: "VmasTask", s: VmasState) -> dict[str, Tensor]:
    """covered: fraction of food with an agent on it (VMAS's eating condition, d < r_agent + r_food)."""
    d = (s.lm_pos[:, :, None, :] - s.pos[:, None, :, :]).norm(dim=-1)  # (B, L, N)
    r = t.radius(s)[:, None, :] + t.lm_radius(s)[:, :, None]
    on = (d < r).any(-1)
    return {"covered": on.float().mean(-1), "success": on.all(-1).float()}


OBJECTIVES: dict[str, Objective] = {
    "goal_distance": Objective(_goal_distance, _on_goal, needs="goal"),
    "coverage": Objective(_coverage, _covered),
    "reward": Objective(lambda t, s: -s.reward.sum(-1), lambda t, s: {}),
}
"""task.cost -> the objective (docs/vmas.md, 'Costs'); every one adds the named shaping collision_weight"""


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
            vmas = _vmas()
            kw = {**self.cfg.scenario_kwargs, self.cfg.size_kwarg: n}
            try:
                self._envs[key] = vmas.make_env(scenario_of(self.cfg.scenario), num_envs=b, device=device,
                                                continuous_actions=True, grad_enabled=True, seed=0, **kw)
            except ConfigError:
                raise
            except Exception as e:  # the scenario's own assertions (a bad kwarg, an impossible size)
                raise ConfigError(f"task.scenario={self.cfg.scenario!r} with {kw}: VMAS refused "
                                  f"({type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''})") from None
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
        s = self._read(self._reset_env(env, 0))
        a = torch.full((1, s.n_agents, 2), 0.1 * self.world.u_range, requires_grad=True)
        nxt = self._physics(env, s, a)
        g = torch.autograd.grad(nxt.pos.sum(), a, allow_unused=True)[0] if nxt.pos.requires_grad else None
        if g is None or not torch.isfinite(g).all() or g.abs().sum() == 0:
            raise ConfigError(f"scenario {self.cfg.scenario!r}: its step passes no gradient from the actions to the "
                              f"positions (non-differentiable dynamics); BPTT cannot train through it")
        if self.cfg.cost == "reward":
            r1, r2 = self._rewards(env), self._rewards(env)
            if not torch.allclose(r1, r2):
                raise ConfigError(f"scenario {self.cfg.scenario!r}: reward() keeps state between calls (two calls "
                                  f"on one world differ), so it is not a function of the state; use task.cost="
                                  f"goal_distance or coverage, or make reward() read only the world")

    def _reset_env(self, env: Any, seed: int) -> Any:
        env.reset(seed=seed, return_observations=False)
        return env

    # --------------------------------------------------------------------- state <-> world
    def _read(self, env: Any) -> VmasState:
        """The world's physical state as a VmasState (after a reset: no graph)."""
        w = env.world

        def stack(ents, attr, d):
            if not ents:
                return torch.zeros(env.num_envs, 0, d, device=env.device)
            return torch.stack([getattr(e.state, attr) if getattr(e.state, attr) is not None
                                else torch.zeros(env.num_envs, d, device=env.device) for e in ents], 1)

        a, lm = w.agents, w.landmarks
        return VmasState(stack(a, "pos", 2), stack(a, "vel", 2), stack(a, "rot", 1), stack(a, "ang_vel", 1),
                         stack(lm, "pos", 2), stack(lm, "vel", 2), stack(lm, "rot", 1), stack(lm, "ang_vel", 1),
                         torch.zeros(env.num_envs, len(a), device=env.device))

    @staticmethod
    def _write(env: Any, s: VmasState) -> None:
        """Put the state into the world. Copies: VMAS may update a state tensor in place; clone keeps the graph."""
        w = env.world
        for ents, fields in ((w.agents, (s.pos, s.vel, s.rot, s.ang_vel)),
                             (w.landmarks, (s.lm_pos, s.lm_vel, s.lm_rot, s.lm_ang_vel))):
            for k, e in enumerate(ents):
                for attr, t in zip(("vel", "pos", "rot", "ang_vel"), (fields[1], fields[0], fields[2], fields[3])):
                    if getattr(e.state, attr) is not None:
                        setattr(e.state, attr, t[:, k].clone())

    def _physics(self, env: Any, s: VmasState, force: Tensor) -> VmasState:
        """One VMAS step from state s with actions (B, N, 2) inside the bounds: VMAS's Environment.step without its
        observations, rewards and dones."""
        self._write(env, s)
        for k, agent in enumerate(env.world.agents):
            env._set_action(force[:, k], agent)
        for agent in env.world.agents:
            env.scenario.env_process_action(agent)
        env.scenario.pre_step()
        env.world.step()
        env.scenario.post_step()
        return self._read(env)

    def _rewards(self, env: Any) -> Tensor:
        return torch.stack([env.scenario.reward(a) for a in env.world.agents], -1)

    # ------------------------------------------------------------------------------ the protocol
    def reset(self, batch: int, gen: torch.Generator) -> list[VmasState]:
        """``batch`` episodes split evenly over team_sizes, one bucket per size. Even, not drawn: a bucket's shape
        (N, B) is then the same at every training step, so each VMAS instance is built once."""
        sizes = self.cfg.sizes
        counts = [batch // len(sizes) + (k < batch % len(sizes)) for k in range(len(sizes))]
        return [self._reset_bucket(n, b, gen) for n, b in zip(sizes, counts) if b]

    def _reset_bucket(self, n: int, b: int, gen: torch.Generator) -> VmasState:
        seed = int(torch.randint(0, 2**31 - 1, (1,), generator=gen))
        env = self._reset_env(self._env(n, b, "cpu"), seed)
        s = self._read(env)
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
            env = self._env(n, b, state.pos.device)
            self._write(env, state)
            parts.append(torch.stack([env.scenario.observation(a) for a in env.world.agents], 1).to(state.pos.dtype))
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
        nxt = self._physics(env, state, self.target(action))
        if self.cfg.cost == "reward":
            nxt = dataclasses.replace(nxt, reward=self._rewards(env))
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
