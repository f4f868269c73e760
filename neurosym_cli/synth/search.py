"""One synthesis run: the search space from the dataset, then the search (MCMC, or the hybrid local search of
local.py) for each communication round."""

from __future__ import annotations

import random
from dataclasses import dataclass
from typing import Callable

import torch

from ..dsl.ast import Program
from ..dsl.sampling import SearchSpace, propose, random_rules
from .local import hybrid
from .mcmc import SearchResult, metropolis
from .objective import CachedScorer


def feature_quantiles(scorer: CachedScorer, gen: torch.Generator, n_q: int = 49,
                      sample: int = 200_000) -> dict[str, tuple[float, ...]]:
    """Empirical quantiles (2%..98%) of every feature over the dataset's pairs (self pairs excluded)."""
    out = {}
    qs = torch.linspace(0.02, 0.98, n_q)
    for name in scorer.data[0].feats.names:
        vals = []
        for d in scorer.data:
            v = d.feats[name].expand(d.s, d.n, d.n)
            off = ~torch.eye(d.n, dtype=torch.bool, device=v.device).expand(d.s, -1, -1)
            flat = v[off]
            idx = torch.randint(0, flat.numel(), (min(sample, flat.numel()),), generator=gen).to(flat.device)
            vals.append(flat[idx].float().cpu())
        q = torch.quantile(torch.cat(vals), qs)
        out[name] = tuple(sorted({round(float(x), 2) + 0.0 for x in q}))
    return out


@dataclass(kw_only=True)
class RoundSpec:
    steps: int
    restarts: int
    final_fraction: float
    temperature: float
    rules: int
    max_depth: int
    det: bool
    own_scores: bool = True
    patience: int = 0
    """proposals without a new chain best that end a phase (0: never)"""
    search: str = "mcmc"
    """mcmc (the paper's Metropolis chains) or hybrid (local.py: hill climbing, fitting, kicks, no program twice)"""
    seconds: float = 0.0
    """hybrid only: wall-clock limit of the round's search (0: the steps alone bound it)"""


def search_round(scorer: CachedScorer, spec: RoundSpec, seed: str, gen: torch.Generator,
                 on_step: Callable | None = None, coarse: CachedScorer | None = None, *,
                 start: tuple | None = None) -> SearchResult:
    """The search (``spec.search``) for one round's rules; ``seed`` fixes every proposal and acceptance draw.
    ``coarse`` (the same objective on a subsample of D) scores MCMC's restarts; the feature quantiles always come
    from the whole of D."""
    vocab = scorer.fmap.vocab
    space = SearchSpace(feature_quantiles(scorer, gen), spec.rules, spec.max_depth, spec.det, spec.own_scores,
                        frozenset(n for n in vocab.names if vocab.agent_level(n)))
    rng = random.Random(seed)
    if spec.search == "hybrid":  # patience, coarse and temperature are MCMC's levers: the hybrid has its own
        return hybrid(lambda: random_rules(space, rng), space, scorer, steps=spec.steps, restarts=spec.restarts,
                      final_fraction=spec.final_fraction, rng=rng, seconds=spec.seconds, on_step=on_step)
    return metropolis(
        init=(lambda: start) if start is not None else (lambda: random_rules(space, rng)),  # start: front.py
        propose=lambda rules: propose(rules, space, rng),
        scorer=scorer, steps=spec.steps, restarts=spec.restarts, final_fraction=spec.final_fraction,
        temperature=spec.temperature, rng=rng, on_step=on_step, patience=spec.patience, coarse=coarse,
    )


def as_program(results: list[SearchResult]) -> Program:
    return Program(tuple(r.best for r in results))
