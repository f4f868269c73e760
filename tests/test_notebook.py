"""examples/tutorial.ipynb runs top to bottom at the tiny budget (write a task, train, synthesize, read, retrain,
evaluate, export and check), every file it writes under a temporary directory."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "tutorial.ipynb"
PARAMETERS = {"work", "budget", "threads"}


def _parameters_cell(nb):
    cells = [c for c in nb.cells if "parameters" in c.get("metadata", {}).get("tags", [])]
    assert len(cells) == 1, "the tutorial has one cell tagged 'parameters' (the test replaces it)"
    return cells[0]


def test_the_tutorial_is_committed_without_outputs():
    nbformat = pytest.importorskip("nbformat", reason="the notebook test needs nbformat (the dev extra)")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(nb)
    assert all(not c.get("outputs") and c.get("execution_count") is None for c in nb.cells if c.cell_type == "code")
    names = {t.id for node in ast.parse(_parameters_cell(nb).source).body if isinstance(node, ast.Assign)
             for t in node.targets if isinstance(t, ast.Name)}
    assert names == PARAMETERS, f"the parameters cell sets {sorted(names)}; the test overrides {sorted(PARAMETERS)}"


@pytest.mark.slow
def test_the_tutorial_runs_at_the_tiny_budget(tmp_path):
    nbformat = pytest.importorskip("nbformat", reason="the notebook test needs nbformat (the dev extra)")
    nbclient = pytest.importorskip("nbclient", reason="the notebook test needs nbclient (the dev extra)")
    pytest.importorskip("ipykernel", reason="the notebook test needs ipykernel (the dev extra)")
    pytest.importorskip("onnx", reason="the tutorial exports the policy, which needs the onnx extra")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    work = tmp_path / "work"
    _parameters_cell(nb).source = f"from pathlib import Path\nwork = Path({str(work)!r})\nbudget = 'tiny'\nthreads = 1\n"
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    last = "".join(o.get("text", "") for o in nb.cells[-1].outputs if o.get("output_type") == "stream")
    assert "tutorial finished" in last and "export check passed" in last, last
    program = work / "outputs" / "gather" / "tiny" / "seed0"
    assert (program / "train" / "oracle" / "model.pt").is_file()
    assert list((program / "export").glob("*/program.py")), "the export folder is under the tmp runs root"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["work"], "the notebook wrote outside its work folder"
