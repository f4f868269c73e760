import os
import sys
from pathlib import Path

import pytest

import neurosym_cli  # noqa: F401  (before torch: pins the CPU kernels of this process, utils/cpu.py)
import torch

ROOT = Path(__file__).resolve().parents[1]

# Tests run one process per core (pytest-xdist, `addopts` in pyproject.toml): each worker, and every CLI subprocess
# it starts (they inherit OMP_NUM_THREADS), gets one torch thread, since oversubscribed OpenMP threads spin and slow
# BPTT down by an order of magnitude (docs/performance.md). Without workers: at most 2 threads, or OMP_NUM_THREADS.
if os.environ.get("PYTEST_XDIST_WORKER"):
    os.environ["OMP_NUM_THREADS"] = "1"
torch.set_num_threads(int(os.environ.get("OMP_NUM_THREADS", max(1, min(2, os.cpu_count() or 1)))))


@pytest.fixture
def gen():
    return torch.Generator().manual_seed(0)


def neurosym_cmd():
    """How to invoke the CLI in a subprocess: the installed script, else the module."""
    exe = Path(sys.executable).parent / "neurosym"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "neurosym_cli.cli"]
