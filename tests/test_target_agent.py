"""A task's target may read each agent's own input s_i: target(action, agent), e.g. a per-agent speed limit (issue 40).
The dataset D, the search's scorer and the exported policy all apply it; a target of the action alone still works."""

import pytest
import torch

from neurosym_cli.config import ModelConfig
from neurosym_cli.dsl import ArgMaxRule, Linear, Program, TrueCond
from neurosym_cli.errors import ConfigError
from neurosym_cli.export.policy import AgentAct, TeamPolicy
from neurosym_cli.policy import CommTransformer
from neurosym_cli.synth.dataset import collect
from neurosym_cli.synth.objective import CachedScorer
from neurosym_cli.tasks import make_task
from neurosym_cli.tasks.base import Rng, applied_action, target_reads_agent
from neurosym_cli.tasks.random_cross import CrossConfig, RandomCrossTask

CPU = torch.device("cpu")
SLOW = 0.1
"""the speed limit of an agent east of its goal (s_i[0] = x_i - g_i > 0)"""


class SlowEast(RandomCrossTask):
    """random-cross where an agent east of its goal flies at most SLOW: a limit that differs per agent."""

    def target(self, action, agent):
        limit = torch.where(agent[..., :1] > 0, SLOW, self.cfg.v_max)
        speed = action.norm(dim=-1, keepdim=True) + 1e-6
        return action * (torch.minimum(speed, limit) / speed)


def _setup(cls=SlowEast):
    env = cls(CrossConfig(name="random-cross", horizon=6))
    torch.manual_seed(0)
    pol = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig(width=16, ffn=32)).eval()
    with torch.no_grad():
        pol.head.weight.mul_(50.0)  # actions well above SLOW, so the limit binds
    return env, pol


def _obeys(action, agent):
    """(fraction of east agents within SLOW, fraction of west agents above it)."""
    speed, east = action.norm(dim=-1), agent[..., 0] > 0
    return float((speed[east] <= SLOW + 1e-5).float().mean()), float((speed[~east] > SLOW).float().mean())


def test_the_two_forms_are_read_once_per_class():
    assert target_reads_agent(SlowEast) and not target_reads_agent(RandomCrossTask)
    env = make_task(CrossConfig(name="random-cross"))
    a, s = 3 * torch.randn(2, 5, 2), torch.randn(2, 5, 2)
    assert torch.equal(applied_action(env)(a, s), env.target(a))  # a target of the action alone ignores s_i

    class NoAction(RandomCrossTask):
        def target(self):
            return None

    with pytest.raises(ConfigError, match="NoAction.target takes no action"):
        target_reads_agent(NoAction)


def test_dataset_and_scorer_apply_a_per_agent_limit():
    env, pol = _setup()
    data = collect(env, pol, 2, 1, torch.Generator().manual_seed(0), CPU)
    for b in data:
        within, above = _obeys(b.target, b.agent)
        assert within == 1.0 and above > 0.5  # the limit holds for the east agents only
    sc = CachedScorer(pol, env, data, round_idx=0, version="v1", lam=0.5, objective="paper", cap=1, samples=1,
                      gen=torch.Generator().manual_seed(0), device=CPU)
    nearest = (ArgMaxRule(Linear((("d", -1.0),)), TrueCond()),)
    inc, full = sc.score(nearest), sc.full_score(Program((nearest,)))
    assert abs(inc.l1 - full.l1) <= 1e-4 * max(1.0, full.l1)  # the cached rows read the same s_i as the full pass


@pytest.mark.filterwarnings("ignore")  # the tracer's notes
def test_the_exported_policy_applies_the_limit_of_its_input():
    env, pol = _setup()
    target = applied_action(env)
    state = env.reset(1, torch.Generator().manual_seed(1))[0]
    obs = env.observe(state, Rng(torch.Generator().manual_seed(2)))
    n = obs.agent.shape[1]
    picks = torch.full((1, 1, n, 1), -1, dtype=torch.long)
    team = TeamPolicy(pol, target).eval()
    traced = torch.jit.trace(team, (obs.agent, obs.rel, picks), check_trace=False)
    for agent in (obs.agent, -obs.agent):  # the traced model reads the limit from its input, not a constant
        action, raw = traced(agent, obs.rel, picks)
        within, above = _obeys(action[0], agent[0])
        assert within == 1.0 and above > 0.5 and not torch.equal(action, raw)
    y = torch.randn(n, 16)
    act, _ = AgentAct(pol, target)(y, obs.agent[0])  # one agent per row, with its own s_i
    assert _obeys(act, obs.agent[0])[0] == 1.0
