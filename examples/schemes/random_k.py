"""A communication scheme of your own, outside the package: every step, each agent hears k others drawn at random
(gossip), under its own transformer.

It shows every part of the scheme boundary (docs/extending.md, section 6):
- the class is the typed schema of its ``baseline=`` option: its field ``k`` is ``baseline.k=3`` on the command line,
  checked and suggested like every key;
- its default ``name`` and its docstring's first line are its name and description in tables and ``--help``;
- ``tag`` and ``train_overrides`` name its model directory (train/random-k-k2/) and the command that makes it;
- ``picks`` is the rule (the sparse path: the transformer computes the B N k picked pairs only); its draws come from
  the episode's random source ``ctx.rng``, so an evaluation seed fixes them.

Run it from this folder (the class is imported from the working directory), or install this folder
(`pip install -e examples/schemes`: its entry point names it `random-k`) and run `baseline=random-k` anywhere:

    neurosym pipeline baseline._target_=random_k.RandomK 'baselines=[tf-full,random-k,no-comm]' budget=tiny
"""

from __future__ import annotations

from dataclasses import dataclass

from neurosym import ConfigError
from neurosym.schemes import OwnRule


@dataclass
class RandomK(OwnRule):
    """its own transformer, each agent hearing k others drawn at random every step (gossip)"""

    name: str = "random-k"
    k: int = 2
    """agents each agent hears per step, drawn uniformly among the others (all of them when k >= N - 1)"""

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.k < 1:
            raise ConfigError(f"baseline.k must be at least 1, got {self.k}")  # one line, exit 2

    def tag(self, cfg) -> str:  # directories train/random-k-k2/, eval/random-k-k2/
        return f"k{self.k}"

    def train_overrides(self, cfg) -> str:  # the `neurosym train` line that makes that model
        return f" baseline.k={self.k}"

    def picks(self, ctx, round):  # (B, N, k) long: the sparse path
        import torch  # a scheme imports torch only when it runs: `neurosym --help` stays fast

        b, n = ctx.obs.agent.shape[:2]
        k = min(self.k, n - 1)
        if k < 1:  # one agent: nobody to hear
            return torch.zeros(b, n, 0, dtype=torch.long, device=ctx.obs.agent.device)
        u = ctx.rng.rand(b, n, n)  # the episode's own random source
        u = u.masked_fill(torch.eye(n, dtype=torch.bool, device=u.device), -1.0)  # never itself
        return u.topk(k, dim=-1).indices  # k distinct others, uniformly at random
