"""examples/benchmarl: a neurosym program as the topology of BenchMARL's GNN. Skipped without benchmarl and
torch_geometric (not extras of neurosym: pip install benchmarl torch_geometric torch==2.13.0)."""

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest
import torch

pytest.importorskip("benchmarl", reason="benchmarl is not installed (examples/benchmarl/README.md)")
pytest.importorskip("torch_geometric", reason="torch_geometric is not installed (examples/benchmarl/README.md)")
pytest.importorskip("vmas", reason="the vmas extra is not installed (pip install -e '.[vmas]')")

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "benchmarl"


def _module():
    spec = importlib.util.spec_from_file_location("program_gnn", EXAMPLE / "program_gnn.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["program_gnn"] = mod  # its dataclass resolves its annotations through sys.modules
    spec.loader.exec_module(mod)
    return mod


def test_the_edges_are_the_programs_picks_from_vmas_observations():
    """Nearest-agent program on hand-made VMAS navigation observations: each agent hears exactly its nearest other
    agent, messages flow j -> i over the batched node index, and the config is registered by name."""
    from benchmarl.models import model_config_registry

    from neurosym_cli.dsl import parse
    from neurosym_cli.tasks import Rng

    mod = _module()
    assert model_config_registry["neurosym_gnn"] is mod.ProgramGnnConfig
    program = parse("argmax(map(-1.0*d, filter(true, l)))")
    fmap = mod.make_task(mod.compose_config("show_program", ["task=vmas/navigation-nolidar"]).task).features("v1")
    gen = torch.Generator().manual_seed(0)
    pos = torch.rand(3, 5, 2, generator=gen) * 2 - 1  # (B, N, 2)
    obs = torch.cat([pos, torch.zeros(3, 5, 2), pos - 0.5, torch.rand(3, 5, 12, generator=gen)], -1)  # + lidar
    edge_index, mask = mod.program_edges(program, fmap, obs, Rng(gen))
    d = torch.cdist(pos, pos) + torch.eye(5) * 1e9
    nearest = d.argmin(-1)  # (B, N)
    assert torch.equal(mask, torch.nn.functional.one_hot(nearest, 5).bool())
    src, dst = edge_index
    assert edge_index.shape == (2, 15) and torch.equal(src % 5, nearest.flatten()[dst])
    assert torch.equal(src // 5, dst // 5)  # never across episodes of the batch


@pytest.mark.slow
def test_the_example_trains_mappo_with_a_program(tmp_path):
    (tmp_path / "p.txt").write_text("random(filter(d <= 0.6, l))\n")
    p = subprocess.run([sys.executable, str(EXAMPLE / "run.py"), str(tmp_path / "p.txt"), "--iters", "1"],
                       capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert p.returncode == 0, p.stderr[-2000:]
    assert "ran 1 iteration(s) of MAPPO with 6 agents" in p.stdout
