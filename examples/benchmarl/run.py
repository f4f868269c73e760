"""Train BenchMARL's MAPPO on VMAS navigation with a neurosym program as the actor GNN's topology (README.md here).

    python examples/benchmarl/run.py PROGRAM.txt                    # 2 iterations of 600 frames: a smoke run
    python examples/benchmarl/run.py PROGRAM.txt --iters 50 --agents 6

PROGRAM.txt is a program `neurosym synth task=vmas/navigation-nolidar` wrote (its features: gx gy gd gtheta, dx dy
d theta, vd, dv). Prints each iteration's mean episode reward and the mean number of agents each agent heard.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import torch  # noqa: E402
import torch_geometric  # noqa: E402
from benchmarl.algorithms import MappoConfig  # noqa: E402
from benchmarl.environments import VmasTask  # noqa: E402
from benchmarl.experiment import Experiment, ExperimentConfig  # noqa: E402
from benchmarl.models import MlpConfig  # noqa: E402

from program_gnn import ProgramGnn, ProgramGnnConfig  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("program", help="a program.txt of task vmas/navigation-nolidar")
    ap.add_argument("--iters", type=int, default=2)
    ap.add_argument("--agents", type=int, default=6)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    torch.set_num_threads(1)

    task = VmasTask.NAVIGATION.get_from_yaml()
    task.config.update(n_agents=a.agents, max_steps=60)
    exp = ExperimentConfig.get_from_yaml()
    for k, v in dict(max_n_iters=a.iters, max_n_frames=None, on_policy_collected_frames_per_batch=600,
                     on_policy_n_envs_per_worker=10, on_policy_n_minibatch_iters=2, on_policy_minibatch_size=200,
                     evaluation=False, render=False, loggers=["csv"], checkpoint_interval=0, create_json=False,
                     save_folder=tempfile.mkdtemp(prefix="neurosym-benchmarl-"), lr=3e-4).items():
        setattr(exp, k, v)
    model = ProgramGnnConfig(topology="full", self_loops=False, gnn_class=torch_geometric.nn.conv.GraphConv,
                             gnn_kwargs={"aggr": "mean"}, program=a.program, program_seed=a.seed)
    experiment = Experiment(task=task, algorithm_config=MappoConfig.get_from_yaml(), model_config=model,
                            critic_model_config=MlpConfig.get_from_yaml(), seed=a.seed, config=exp)

    actor = next(m for m in experiment.policy.modules() if isinstance(m, ProgramGnn))
    experiment.run()
    print(f"ran {a.iters} iteration(s) of MAPPO with {a.agents} agents; the program's edges: each agent heard "
          f"{sum(actor.in_degrees) / max(len(actor.in_degrees), 1):.2f} agents on average over "
          f"{len(actor.in_degrees)} forward passes")
    print(f"BenchMARL's csv logs: {exp.save_folder}")


if __name__ == "__main__":
    main()
