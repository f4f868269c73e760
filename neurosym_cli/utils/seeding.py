"""Seeding: one seed fixes numpy, torch (dropout) and every generator derived from it."""

from __future__ import annotations

import random

import numpy as np
import torch

# distinct streams derived from one user seed, so e.g. evaluation episodes never reuse training draws
STREAM_TRAIN, STREAM_EVAL, STREAM_SYNTH_DATA, STREAM_SYNTH = 1, 2, 3, 4
STREAM_VAL = 5  # validation episodes of `neurosym select`: never a test (STREAM_EVAL) episode


def seed_everything(seed: int) -> None:
    random.seed(seed)
    np.random.seed(seed % 2**32)
    torch.manual_seed(seed)


def generator(seed: int, *stream: int) -> torch.Generator:
    """A CPU generator for (seed, stream...) that does not depend on any other draw."""
    g = torch.Generator()
    h = seed
    for s in stream:
        h = (h * 1_000_003 + s + 0x9E3779B9) % (2**63 - 1)
    g.manual_seed(h)
    return g
