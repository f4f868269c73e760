"""A neurosym program as the communication topology of BenchMARL's GNN (examples/benchmarl/README.md).

BenchMARL's ``Gnn`` offers the topologies ``full``, ``empty`` and ``from_pos`` (within a radius). ``ProgramGnn`` is
the same model with the edges chosen by a synthesized program instead: at every forward pass, agent i hears the
agents the program's rules pick for it from the current observations (paper section 3.2), and the GNN passes
messages along exactly those edges (j -> i). The program is read from a ``program.txt`` that `neurosym synth` wrote
for a neurosym task with the same observation geometry (here ``vmas/navigation-nolidar``: s_i = [g_i - x_i, v_i],
o_ij = [x_j - x_i, v_j - v_i]), and evaluated by neurosym's own interpreter, so the edges are the ones neurosym's
evaluation would draw.

The observation is VMAS navigation's flat one as BenchMARL passes it: columns 0:2 position, 2:4 velocity, 4:6
x_i - g_i (then the lidar, which the program does not read). ``ProgramGnnConfig`` is registered in BenchMARL's
``model_config_registry`` as ``neurosym_gnn`` when this module is imported.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import torch
from benchmarl.models import model_config_registry
from benchmarl.models.gnn import Gnn, GnnConfig
from tensordict import TensorDictBase

from neurosym_cli.commands.apps import compose_config
from neurosym_cli.dsl.files import load_program
from neurosym_cli.dsl.interpret import program_mask
from neurosym_cli.tasks import Rng, make_task

POS, VEL, GOAL_OFFSET = slice(0, 2), slice(2, 4), slice(4, 6)  # VMAS navigation's observation columns


def program_edges(program, fmap, obs: torch.Tensor, rng: Rng) -> tuple[torch.Tensor, torch.Tensor]:
    """obs (B, N, D) VMAS navigation observations -> (edge_index (2, E) over the B * N nodes, source j -> target i,
    and the (B, N, N) mask: i hears j), the program's first round evaluated on neurosym's features."""
    b, n = obs.shape[:2]
    agent = torch.cat([-obs[..., GOAL_OFFSET], obs[..., VEL]], -1)  # s_i = [g_i - x_i, v_i]  (B, N, 4)
    pos, vel = obs[..., POS], obs[..., VEL]
    rel = torch.cat([pos[:, None] - pos[:, :, None], vel[:, None] - vel[:, :, None]], -1)  # [i, j] = x_j - x_i
    mask = program_mask(program, 0, fmap.view(agent, rel), rng)  # (B, N, N)
    e, i, j = mask.nonzero(as_tuple=True)
    return torch.stack([e * n + j, e * n + i]), mask


class ProgramGnn(Gnn):
    """BenchMARL's Gnn (shared parameters, decentralised) with edges from a neurosym program."""

    def __init__(self, program: str, neurosym_task: str, program_seed: int = 0, **kwargs):
        super().__init__(**kwargs)
        if not program:
            raise ValueError("ProgramGnnConfig.program: the path of a program.txt (neurosym synth writes one)")
        if not self.share_params or self.centralised:
            raise ValueError("ProgramGnn supports share_params=True with a decentralised actor (one GNN for all)")
        self.program = load_program(Path(program))
        if self.program.n_rounds != 1:
            raise ValueError(f"{program}: ProgramGnn runs one round of communication; the program has "
                             f"{self.program.n_rounds}")
        self.fmap = make_task(compose_config("show_program", [f"task={neurosym_task}"]).task).features("v1")
        self.rng = Rng(torch.Generator().manual_seed(program_seed))  # random rules draw from here
        self.in_degrees: list[float] = []  # mean number of agents each agent heard, per forward pass

    def _forward(self, tensordict: TensorDictBase) -> TensorDictBase:
        obs = torch.cat([tensordict.get(k) for k in self.in_keys], -1)  # (*B, N, D)
        batch, n = obs.shape[:-2], obs.shape[-2]
        flat = obs.reshape(-1, n, obs.shape[-1])
        with torch.no_grad():  # the topology is a discrete choice: no gradient through it
            edge_index, mask = program_edges(self.program, self.fmap, flat, self.rng)
        self.in_degrees.append(float(mask.sum(-1).float().mean()))
        out = self.gnns[0](x=flat.reshape(-1, flat.shape[-1]), edge_index=edge_index.to(flat.device))
        tensordict.set(self.out_key, out.view(*batch, n, self.output_features))
        return tensordict


@dataclass
class ProgramGnnConfig(GnnConfig):
    """GnnConfig plus the program: ``program`` a program.txt path, ``neurosym_task`` the neurosym task whose
    features it reads. ``topology`` is only BenchMARL's placeholder ("full"): the program replaces the edges."""

    program: str = ""
    neurosym_task: str = "vmas/navigation-nolidar"
    program_seed: int = 0

    @staticmethod
    def associated_class():
        return ProgramGnn


model_config_registry["neurosym_gnn"] = ProgramGnnConfig
