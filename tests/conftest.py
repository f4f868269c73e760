import json
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
# A pipeline runs its stages one after the other in its own process here (the cores are the test workers'; a worker
# process per stage would cost an import of torch each): tests of pipeline.jobs > 1 say so (tests/test_flow.py).
os.environ.setdefault("NEUROSYM_PIPELINE_JOBS", "1")


@pytest.fixture
def gen():
    return torch.Generator().manual_seed(0)


def neurosym_cmd():
    """How to invoke the CLI in a subprocess: the installed script, else the module."""
    exe = Path(sys.executable).parent / "neurosym"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "neurosym_cli.cli"]


# --- issue 37's defaults and the paper's method -------------------------------------------------------------------
if str(ROOT) not in sys.path:  # benchmarks/ (a folder at the repository's root) imports under a plain `pytest` too
    sys.path.append(str(ROOT))
from benchmarks.run_seeds import PAPER_METHOD  # noqa: E402,F401  (written there once)

# PAPER_METHOD, synth.search=mcmc synth.front=false pipeline.select=none: what a test about something other than the
# defaults passes when its premise is the paper's programs and labels (synth/k2-lam0.5-v1, eval/prog-k2-lam0.5-v1)
# rather than today's (the hybrid search's k2-lam0.5-v1-hybrid; the pipeline's prog under the front's pick).


def run_dir(cmd: str, runs, *overrides: str, config_dir=None):
    """The RunDir of the config `neurosym <cmd> <overrides>` composes under the runs root ``runs`` (its program's
    tag, label, model and files as the command names them); ``config_dir``: its --config-dir (a plugin task)."""
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.run import RunDir

    return RunDir(compose_config(cmd, [f"runs_root={runs}", *overrides], config_dir=config_dir))


def front_pick(runs, *overrides: str) -> dict:
    """The pipeline's front selection of the run of ``overrides`` (pipeline.select=front, the default): the
    ``picked`` row of select/front/<tag>.json (name, budget, program_file, label, program, degree, loss_mean)."""
    search = run_dir("synth", runs, *overrides)
    return json.loads(search.front_choice_file(search.program_tag).read_text())["picked"]


def picked_labels(runs, *overrides: str) -> dict[str, str]:
    """prog and prog-retrained -> the label the pipeline evaluates them under: the front's pick run as program=
    (prog-file-<tag>-<name>-<sha1:8>-<features>, name b<budget> or near<budget>)."""
    program = front_pick(runs, *overrides)["program_file"]
    return {b: run_dir("eval", runs, *overrides, f"baseline={b}", f"program={program}").label
            for b in ("prog", "prog-retrained")}
