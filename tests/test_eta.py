"""Time-left estimates settle within a few steps (issue 40): the warm-up step is left out, the pace is a running
mean that follows a drift; the pipeline's overall time left comes from its stages' measured pace."""

import pytest

from neurosym_cli.utils.console import Eta, left_text


def _run(times, total, **kw):
    """Feed step times (seconds) to an Eta; its estimate after each step."""
    eta, now, out = Eta(total, now=0.0, **kw), 0.0, []
    for k, dt in enumerate(times, start=1):
        now += dt
        out.append(eta.update(k, now))
    return out


def test_a_slow_first_step_does_not_inflate_the_estimate():
    total = 1000
    est = _run([10.0, 1.0, 1.0], total)  # the first step 10 times a later one (kernels compiled, caches filled)
    truth = total - 3  # 1 s per step from here on
    assert est[0] is None and left_text(est[0]) == "?"  # nothing measured past the warm-up yet
    assert abs(est[2] - truth) <= 0.2 * truth
    naive = 12.0 / 3 * (total - 3)  # elapsed / steps, the estimate before: 4 times the truth
    assert abs(naive - truth) > 0.2 * truth


def test_the_estimate_follows_a_pace_that_changes_and_steps_reported_in_jumps():
    est = _run([5.0] + [1.0] * 20 + [2.0] * 40, 200)
    assert est[20] == pytest.approx(200 - 21)
    assert est[-1] == pytest.approx(2.0 * (200 - 61), rel=0.1)  # now 2 s a step
    eta = Eta(100, start=40, now=0.0)  # a resumed run: steps 41.. are this run's
    assert eta.update(45, 50.0) is None  # the interval holding the warm-up step is not measured
    assert eta.update(50, 55.0) == pytest.approx(50.0)  # 1 s a step, 50 steps left


def test_the_pipelines_time_left_scales_the_measured_pace_by_the_rough_cost_model():
    from neurosym_cli.stages.pipeline import WEIGHTS, PipelineClock

    pace = PipelineClock()
    remaining = [("train", 1000, None), ("synth", 1500, None), ("eval", 20, None)]
    assert pace.left(remaining) is None  # nothing measured yet, no earlier run
    assert pace.left([("train", 1000, 200.0), ("eval", 20, 9.0)]) == 209.0  # the times of an earlier run
    pace.done("train", 1000, 300.0)  # the oracle: 0.3 s a rollout
    pace.done("synth", 1500, 0.2)  # a reused search (under a second): no pace
    assert pace.left(remaining) == pytest.approx(300.0 + 0.3 * (WEIGHTS["synth"] * 1500 + WEIGHTS["eval"] * 20))
    assert pace.left([("train", 1000, 200.0), ("eval", 20, 9.0)]) == pytest.approx(300.0 + 9.0)  # measured first
    pace.done("synth", 1500, 30.0)  # a search measured: its own pace from now on
    assert pace.left([("synth", 3000, None), ("train", 0, None)]) == pytest.approx(60.0)  # reused training: 0
