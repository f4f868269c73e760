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
