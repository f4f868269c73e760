"""The communication-provider protocol (policy/protocol.py) over every registered scheme's provider, the link-failure
wrapper without attribute forwarding, and TaskConfig.max_agents: the K < N and memory checks for a task config
that does not state it."""

import dataclasses
import json

import pytest
import torch

from neurosym_cli.commands.apps import compose_config
from neurosym_cli.config import ConfigError, RunConfig, TaskConfig
from neurosym_cli.dsl.interpret import picks_to_mask
from neurosym_cli.policy.comm import CommBase, CommContext, FullComm, LinkFailure, NearestComm, comm_module, \
    with_link_failure
from neurosym_cli.policy.protocol import CommWrapper, unwrap
from neurosym_cli.run.models import check_memory
from neurosym_cli.schemes import SCHEMES
from neurosym_cli.synth.tree import TreeModel
from neurosym_cli.tasks import Rng, make_task, probe
from neurosym_cli.tasks.formation import FormationState
from neurosym_cli.tasks.random_cross import CrossConfig
from plugin_schemes import ALL_SCHEMES, use

PROGRAM = "argmax(map(-1.0*d, filter(d >= 0.0, l)))\n"  # deterministic: each agent hears its nearest


def _provider(name: str, tmp_path):
    """(cfg, provider) of a registered scheme on random-cross; a searched scheme gets a program or tree file."""
    cfg = compose_config("eval", ["task=random-cross", "budget=tiny", f"baseline={name}", f"runs_root={tmp_path}"])
    env = make_task(cfg.task, cfg.horizon)
    art = cfg.baseline.artifact(cfg)
    if art is None:
        return cfg, cfg.baseline.provider(cfg, env)
    path = tmp_path / art.file
    if art.file == "program.txt":
        path.write_text(PROGRAM)
    else:  # one leaf: every pair heard
        leaf = TreeModel(["d"], [-1], [-1], [-2], [-2.0], [True])
        path.write_text(json.dumps({"rounds": [leaf.to_dict()] * cfg.task.rounds}))
    return cfg, cfg.baseline.provider(cfg, env, artifact=path)


def _ctx(n: int = 7, batch: int = 3, seed: int = 0) -> CommContext:
    env = make_task(CrossConfig(name="c", noise_std=0.0))
    g = torch.Generator().manual_seed(seed)
    pos = torch.rand(batch, n, 2, generator=g) * 4
    state = FormationState(pos, pos.clone(), torch.zeros(batch, n, dtype=torch.long))
    return CommContext(env, state, env.observe(state, Rng(g)), Rng(g), 0)


@pytest.mark.parametrize("name", ALL_SCHEMES)
def test_every_schemes_provider_satisfies_the_protocol(name, tmp_path, monkeypatch):
    use(name, monkeypatch)  # the example plugin (examples/schemes) beside the built-in ones
    cfg, comm = _provider(name, tmp_path)
    assert isinstance(comm, CommBase)
    assert isinstance(comm.name, str) and comm.name and comm.inner is None and unwrap(comm) is comm
    assert isinstance(comm.picks_first, bool)
    b, n = 3, 7
    logits = torch.randn(b, n, n, generator=torch.Generator().manual_seed(1))
    with torch.no_grad():
        pk = comm.picks(_ctx(n), 0)
        mask = comm.select(_ctx(n), logits, 0)
        assert comm.pop_step() is None  # nothing recorded without gradients (rl's gate included)
    assert comm.picks_first == (pk is not None)  # picks_first says which path the provider takes
    assert mask.shape == (b, n, n) and mask.dtype == torch.bool and not mask.diagonal(dim1=1, dim2=2).any()
    if pk is not None:
        assert pk.dtype == torch.long and pk.shape[:2] == (b, n) and bool(((pk >= -1) & (pk < n)).all())
        assert torch.equal(mask, picks_to_mask(pk, n))  # the same selection, either way
    # through link failure (twice): the same provider underneath, every member answered by the wrapper itself
    lossy = LinkFailure(LinkFailure(comm, 0.3), 0.5)
    assert unwrap(lossy) is comm and lossy.inner.inner is comm
    assert lossy.name == comm.name and lossy.picks_first == comm.picks_first and lossy.pop_step() is None
    assert comm_module(lossy) is comm_module(comm)
    assert (comm_module(comm) is not None) == (name == "rl")
    with torch.no_grad():
        lost = lossy.select(_ctx(n), logits, 0)
    assert not (lost & ~comm.select(_ctx(n), logits, 0)).any() or name == "rl"  # rl samples: no comparison
    # what the schemes read through the wrapper: K and identity of a program
    if cfg.baseline.has_program:
        assert cfg.baseline.rules(cfg, lossy) == comm.program.max_rules == 1
        assert cfg.baseline.artifact_identity(cfg, lossy) == cfg.baseline.artifact_identity(cfg, comm)


def test_link_failure_forwards_no_attributes():
    assert not hasattr(LinkFailure, "__getattr__") and not hasattr(CommWrapper, "__getattr__")
    inner = NearestComm(3)
    lossy = LinkFailure(inner, 0.5)
    with pytest.raises(AttributeError):
        lossy.k  # the inner provider's k: reached by unwrap(lossy).k, not through the wrapper
    assert unwrap(lossy).k == 3


def test_a_gate_under_link_failure_still_reports_its_decisions():
    from neurosym_cli.policy.gated import GatedComm

    gate = GatedComm(rounds=1)
    lossy = LinkFailure(gate, 0.5)
    assert not lossy.picks_first and comm_module(lossy) is gate
    ctx = _ctx(5)
    lossy.select(ctx, torch.zeros(3, 5, 5), 0)  # gradients on: the gate records its decisions
    logp, deg = lossy.pop_step()
    assert logp.shape == deg.shape == (3,) and lossy.pop_step() is None


def test_a_provider_outside_the_protocol_is_one_line():
    class Bare:  # the old three-member protocol, no CommBase
        name = "bare"

        def select(self, ctx, logits, round):
            return logits > 0

    with pytest.raises(ConfigError, match="not a neurosym_cli.policy.CommBase") as e:
        with_link_failure(Bare(), 0.0)
    assert "\n" not in str(e.value)
    assert with_link_failure(FullComm(), 0.0).name == "full"


# --- TaskConfig.max_agents ----------------------------------------------------------------------------------------

@dataclasses.dataclass
class SoloConfig(TaskConfig):
    """A user's schema that does not state max_agents: one group of agents_per_group."""

    _target_: str = "mine.Solo"
    name: str = "solo"


def test_a_task_config_without_max_agents_still_gets_the_k_below_n_check():
    assert SoloConfig(agents_per_group=4).max_agents == 4
    assert RunConfig(task=SoloConfig(agents_per_group=4), rules=3).rules == 3
    with pytest.raises(ConfigError, match=r"rules=4: an agent of solo has at most 4 - 1 others"):
        RunConfig(task=SoloConfig(agents_per_group=4), rules=4)


def test_a_task_config_without_max_agents_still_gets_the_memory_check():
    cfg = compose_config("train", ["task=random-cross", "budget=tiny"])
    cfg = dataclasses.replace(cfg, task=SoloConfig(agents_per_group=10 ** 7))
    with pytest.raises(ConfigError, match="N = 10,000,000 agents does not fit"):
        check_memory(cfg, make_task(CrossConfig(name="c")), FullComm(), training=True)


def test_every_built_in_task_states_its_largest_team():
    for name in ("random-cross", "two-groups-cross", "random-grid", "unlabeled-goals", "swarm"):
        task = compose_config("train", [f"task={name}"]).task
        env = make_task(task, 2)
        most = max(b.n_agents for b in env.reset(16, torch.Generator().manual_seed(0)))
        assert most <= task.max_agents, name
        probe(env, name, max_agents=task.max_agents)
    cross = compose_config("train", ["task=random-cross"]).task
    assert cross.max_agents == cross.num_groups * cross.agents_per_group > cross.agents_per_group


def test_a_task_that_outgrows_its_max_agents_is_one_line():
    env = make_task(CrossConfig(name="c", group_prob=1.0))  # every group present: N = 4 x agents_per_group
    with pytest.raises(ConfigError, match="made an episode of 40 agents, but its config's max_agents is 10") as e:
        probe(env, "c", max_agents=10)
    assert "\n" not in str(e.value) and "max_agents property" in str(e.value)
