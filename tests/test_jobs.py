"""The grid verbs' process pool (stages/jobs.py): results in the given order, a job's UserError stops the grid in
one line naming the config, and what select and rl hand the spawned workers pickles."""

import pickle

import pytest

from neurosym_cli.config import UserError
from neurosym_cli.stages import RunInfo
from neurosym_cli.stages.jobs import run_jobs


def _square(x, info):
    if x == 3:
        raise UserError("three is refused")
    return {"name": f"p{x}", "value": x * x}


def test_results_come_back_in_order_and_a_user_error_names_its_config():
    rows = run_jobs(_square, [2, 0, 1], RunInfo(), 1, "square", name=lambda x: f"p{x}")
    assert [r["value"] for r in rows] == [4, 0, 1]
    with pytest.raises(UserError, match="^square p3: three is refused$"):
        run_jobs(_square, [1, 3, 2], RunInfo(), 1, "square", name=lambda x: f"p{x}")


def test_the_pool_needs_names_by_keyword():
    with pytest.raises(TypeError):
        run_jobs(_square, [1], RunInfo(), 1, "square", str)  # type: ignore[misc]


def test_what_select_and_rl_send_to_workers_pickles():
    """A spawned worker receives the job function and the naming function pickled (a lambda would fail there)."""
    from neurosym_cli.stages import rl, select

    for f in (select.search_job, select.retrain_job, select.point_name, rl.rl_job, rl.setting_name):
        assert pickle.loads(pickle.dumps(f)) is f
