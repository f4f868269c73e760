"""The swarm task (tasks/swarm.py): two fronts crossing, a world that grows with N at a fixed density."""

import dataclasses

import pytest
import torch

from neurosym_cli.errors import ConfigError
from neurosym_cli.tasks.swarm import SwarmConfig, SwarmTask

SWARM = SwarmConfig(name="swarm")


@pytest.mark.parametrize("groups, n", [(2, 2), (2, 20), (3, 7), (2, 400)])
def test_swarm_layout_separation_and_a_flight_that_does_not_grow_with_n(groups, n):
    env = SwarmTask(dataclasses.replace(SWARM, num_groups=groups, agents_per_group=n))
    s = env.reset(3, torch.Generator().manual_seed(0))[0]
    assert s.pos.shape == (3, groups * n, 2) and s.goal.shape == s.pos.shape
    for b in range(3):
        for pts in (s.pos[b], s.goal[b]):
            d = torch.cdist(pts, pts) + torch.eye(groups * n) * 1e9
            assert d.min() >= SWARM.min_separation - 1e-5
        south = s.group[b] % 2 == 0
        # even groups start south of the gap and fly north; odd ones the other way; blocks SWARM.depth deep
        assert (s.pos[b, south, 1] < -SWARM.gap / 2 + 1e-5).all() and (s.goal[b, south, 1] > SWARM.gap / 2 - 1e-5).all()
        assert (s.pos[b, ~south, 1] > SWARM.gap / 2 - 1e-5).all() and (s.goal[b, ~south, 1] < -SWARM.gap / 2).all()
        assert s.pos[b, :, 1].abs().max() <= SWARM.gap / 2 + SWARM.depth + 1e-5
    flight = (s.pos - s.goal).norm(dim=-1)
    assert flight.max() <= SWARM.gap + 2 * SWARM.depth + 2.0  # straight across, whatever N
    # the density: agents per square unit of the blocks' lattice, 1 / spacing^2
    assert torch.unique(s.group).tolist() == list(range(groups))


def test_swarm_is_random_per_generator_and_groups_of_any_size():
    env = SwarmTask(dataclasses.replace(SWARM, agents_per_group=13))
    a = env.reset(2, torch.Generator().manual_seed(0))[0]
    b = env.reset(2, torch.Generator().manual_seed(0))[0]
    c = env.reset(2, torch.Generator().manual_seed(1))[0]
    assert torch.equal(a.pos, b.pos) and not torch.equal(a.pos, c.pos)
    assert not torch.equal(a.pos[0], a.pos[1])


def test_a_density_too_high_for_the_separation_is_one_line():
    with pytest.raises(ConfigError, match="lower the density to at most 4"):
        SwarmConfig(name="swarm", density=5.0)


def test_a_team_that_cannot_fit_is_one_line_with_the_estimate_and_the_largest_that_fits():
    from neurosym_cli.config import ModelConfig
    from neurosym_cli.policy.footprint import DoesNotFit, estimate_bytes, require_fits

    args = dict(batch=2, horizon=200, rounds=1, model=ModelConfig(), k=2, training=True, sparse_from=256)
    limit = 8 * 2 ** 30
    with pytest.raises(ConfigError, match=r"N = 3,000 agents does not fit: tf-full training needs about [\d.]+ GB "
                                          r"\(2 episode\(s\) at once, T = 200 steps kept for BPTT\), 8.0 GB are "
                                          r"available; the largest team that fits is N = ([\d,]+)") as e:
        require_fits("tf-full training", 3000, dense=True, limit=limit, **args)
    assert isinstance(e.value, DoesNotFit) and "\n" not in str(e.value)
    best = int(str(e.value).split("fits is N = ")[1].split(" ")[0].replace(",", ""))
    assert estimate_bytes(best, dense=True, **args) <= limit < estimate_bytes(best + 1, dense=True, **args)
    # the sparse path of a program fits the same team easily: O(N K) pairs per step instead of N^2
    assert require_fits("prog training", 3000, dense=False, limit=limit, **args) < limit


def test_the_cli_refuses_a_team_that_cannot_fit_before_allocating(tmp_path):
    import subprocess

    from conftest import neurosym_cmd

    r = subprocess.run(neurosym_cmd() + ["train", "task=swarm", "budget=tiny", "task.agents_per_group=15000",
                                         f"runs_root={tmp_path}", "threads=1"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode != 0
    lines = [ln for ln in r.stderr.strip().splitlines() if "warning" not in ln]
    assert len(lines) == 1 and "N = 30,000 agents does not fit" in lines[0] and "largest team that fits" in lines[0]
    assert "Traceback" not in r.stderr


MEMORY_PROBE = """
import sys
import neurosym_cli
import torch
from neurosym_cli.config import ModelConfig
from neurosym_cli.dsl.parser import parse
from neurosym_cli.policy.comm import ProgramComm
from neurosym_cli.policy.transformer import CommTransformer
from neurosym_cli.rollout import rollout
from neurosym_cli.tasks.base import Rng
from neurosym_cli.tasks.swarm import SwarmConfig, SwarmTask
torch.set_num_threads(1)


def high_water_kib():
    # VmHWM belongs to this address space; ru_maxrss would carry over the parent's peak through fork + exec
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))


env = SwarmTask(SwarmConfig(name="swarm", agents_per_group=500))
policy = CommTransformer.for_task(env, ModelConfig()).eval()
comm = ProgramComm(parse("argmax(map(-1.0*d, filter(theta >= -1.85, l)))\\nrandom(filter(d >= 3.6, l))"),
                   env.features("v1"))
state = env.reset(1, torch.Generator().manual_seed(0))[0]
before = high_water_kib()
with torch.no_grad():
    traj = rollout(env, policy, comm, state, Rng([torch.Generator().manual_seed(1)]), 3)
assert traj.max_in.max() == 2
print(before, high_water_kib())
"""


def test_an_evaluation_step_of_a_thousand_agents_stays_under_its_memory_bound():
    """Peak resident memory of a process evaluating 3 steps of N = 1,000 under a program (the sparse path), against
    the bound docs/performance.md section 15 states: 1 GiB in all, and under 300 MiB above what the process held
    before the rollout (interpreter, torch, numba). The dense path would hold (N, N, D) keys alone: 64 MB a round."""
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-c", MEMORY_PROBE], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    before, peak = (int(v) * 1024 for v in r.stdout.split())
    assert peak < 2 ** 30 and peak - before < 300 * 2 ** 20, (before / 2 ** 20, peak / 2 ** 20)
