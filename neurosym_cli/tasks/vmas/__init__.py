"""VMAS scenarios as neurosym tasks: BPTT through VMAS's differentiable physics (``make_env(grad_enabled=True)``).

VMAS (proroklab/VectorizedMultiAgentSimulator, GPLv3, the optional extra ``pip install -e '.[vmas]'``) keeps its
state in a mutable ``World``; neurosym's tasks are pure functions of a :class:`TaskState`. The adapter is the
functional contract between the two (docs/vmas.md, 'The functional contract'). The package, by concept:

- ``scenarios``: importing VMAS (or the one line naming the extra) and finding a scenario by name or
  ``module:Class``;
- ``world``: :class:`VmasState` and the bridge between it and VMAS's mutable world (write, step, read back);
- ``objectives``: the vectors of s_i and the differentiable costs with their success metrics;
- ``task``: the schema :class:`VmasConfig` and the task :class:`VmasTask` (the protocol).

How the bridge keeps the contract:

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

from .objectives import OBJECTIVES, VECTORS, Objective, Vector
from .scenarios import EXTRA, builtin_scenarios, scenario_of
from .task import VmasConfig, VmasTask
from .world import VmasState, World

__all__ = ["EXTRA", "OBJECTIVES", "VECTORS", "Objective", "Vector", "VmasConfig", "VmasState", "VmasTask", "World",
           "builtin_scenarios", "scenario_of"]
