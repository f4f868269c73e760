"""Issue 38, runs that cannot be told apart: a resume under other CPU kernels, VMAS scenario settings replaced or
misspelt."""

import pytest
import torch

from test_plugins import one_line, run


def test_a_resume_under_other_cpu_kernels_is_refused(tmp_path):
    """Steps under avx2 then under native would be a run neither mode makes, recorded as the last mode only."""
    common = ["train", "task=random-grid", "budget=tiny", "plots=false", "threads=1"]
    run(common, tmp_path)
    ckpt = tmp_path / "random-grid/tiny/seed0/train/oracle/model.pt"
    before = ckpt.read_bytes()
    line = one_line(run([*common, "budget.train_rollouts=16", "cpu_kernels=native"], tmp_path, check=False))
    assert "trained for 2 steps under cpu_kernels=avx2, this run has cpu_kernels=native" in line, line
    assert "cpu_kernels=avx2" in line and "overwrite=true" in line and ckpt.read_bytes() == before
    run([*common, "budget.train_rollouts=16"], tmp_path)  # under its own mode it resumes
    payload = torch.load(ckpt, weights_only=True)
    assert payload["fit"]["step"] == 4 and payload["config"]["cpu_kernels"] == "avx2"
