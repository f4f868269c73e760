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


needs_vmas = pytest.mark.skipif(__import__("importlib.util").util.find_spec("vmas") is None,
                                reason="the vmas extra is not installed (pip install -e '.[vmas]')")


@needs_vmas
def test_vmas_scenario_kwargs_are_neither_replaced_nor_misspelt():
    """n_agents in scenario_kwargs was replaced by the team size without a word; a misspelt keyword reached VMAS,
    which warned in several raw lines and trained without it."""
    import warnings

    from neurosym_cli.errors import ConfigError
    from neurosym_cli.tasks.vmas import VmasConfig, VmasTask

    with pytest.raises(ConfigError) as e:
        VmasConfig(scenario_kwargs={"n_agents": 6})
    assert "task.scenario_kwargs.n_agents would be replaced" in str(e.value)
    assert "task.agents_per_group=6" in str(e.value)
    with pytest.raises(ConfigError) as e:
        VmasTask(VmasConfig(scenario_kwargs={"n_lidar_ray": 6, "collisions": False})).reset(2, torch.Generator())
    msg = str(e.value)
    assert "\n" not in msg and "does not use 'n_lidar_ray'" in msg and "did you mean 'n_lidar_rays'" in msg
    assert "'collisions'" not in msg.split("it reads")[0]  # the keyword it does read is not named as unused
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a keyword it reads: no warning, no error
        task = VmasTask(VmasConfig(scenario_kwargs={"n_lidar_rays": 6}))
        task.reset(2, torch.Generator().manual_seed(0))
