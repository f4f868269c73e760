"""A program's filter scan over a large team without the (B, N, N) features (the sparse path, tasks/pairs.py).

The rules of a program read features of every pair (i, j) to decide whom i asks (paper section 3.2): that scan is
the one quadratic part left under a program. Here it runs without gradients (picks are indices) over chunks of
receivers, each chunk's features built from the pair source's rows and dropped before the next, so its memory is
bounded by ``tasks.pairs.PAIR_CHUNK`` pairs whatever N is. A random rule's uniforms come from counters
(``counter_uniform`` of a key per rule and episode drawn from the bucket's random source, and i N + j), so the
picks do not depend on the chunk size.
"""

from __future__ import annotations

import torch
from torch import Tensor

from ..dsl.ast import Program, RandomRule
from ..dsl.interpret import program_picks
from ..tasks.base import Observation, Rng
from ..tasks.features import FeatureMap
from ..tasks.pairs import rows_per_chunk, uniform_rows


class _RowUniforms:
    """The uniforms of a chunk of receivers: the k-th ``rand`` call of a chunk serves the round's k-th random rule
    (program_picks evaluates the rules in order, each random rule drawing once)."""

    def __init__(self, keys: list[Tensor], first: int, stop: int, n: int):
        self.keys, self.first, self.stop, self.n, self.calls = keys, first, stop, n, 0

    def rand(self, batch: int, rows: int, n: int) -> Tensor:
        key = self.keys[self.calls]
        self.calls += 1
        return uniform_rows(key, self.first, self.stop, self.n)  # (B, R, N)


def scan_program(program: Program, round: int, fmap: FeatureMap, obs: Observation, rng: Rng) -> Tensor:
    """(B, N, K) long: the agent each rule of program round ``round`` picks for each agent (-1 for nobody), from
    an observation given as a pair source (``obs.pairs``), in chunks of receivers under no_grad."""
    assert obs.pairs is not None, "scan_program reads a pair source (tasks/pairs.py Offsets)"
    b, n = obs.agent.shape[:2]
    keys = [rng.keys(b) for r in program.rounds[round] if isinstance(r, RandomRule)]  # one per random rule
    c = rows_per_chunk(b, n)
    out = []
    with torch.no_grad():
        for i in range(0, n, c):
            stop = min(i + c, n)
            feats = fmap.view(obs.agent[:, i:stop], obs.pairs.rows(i, stop), first=i)
            out.append(program_picks(program, round, feats, _RowUniforms(keys, i, stop, n)))
    return torch.cat(out, 1)
