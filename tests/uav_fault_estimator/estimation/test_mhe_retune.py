"""Weights and tolerances changed while the estimator runs (mhe_node's live parameters):
applied from the next update with the window kept; what shapes the QP is refused."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers.synthetic_residuals import FAULTS, config, estimator, sequence
from uav_fault_estimator.estimation.estimator_config import SolverSettings
from uav_fault_estimator.estimation.solve_status import SolveStatus

HORIZON = config().horizon


@pytest.mark.timeout(60)
def test_a_new_noise_factor_reweights_the_window_as_if_its_samples_came_with_it():
    """Over the first N updates nothing leaves the window, so the arrival cost holds no data
    yet: an estimator retuned to 4 Q after N samples has exactly the problem of one that
    ran with 4 Q from the start, and both estimate the same from then on."""
    y, s, _ = sequence()
    retuned, reference = estimator(), estimator(noise_variance_factor=4.0)
    for k in range(HORIZON):
        retuned.update(y[k], s[k])
        reference.update(y[k], s[k], noise_variances=np.asarray(reference.config.q_diag))
    retuned.retune(config(noise_variance_factor=4.0))
    gaps = []
    for k in range(HORIZON, len(y)):
        expected = reference.update(y[k], s[k])
        result = retuned.update(y[k], s[k])
        assert result.status is expected.status is SolveStatus.SOLVED
        gaps.append(np.abs(result.window_pct - expected.window_pct).max())
    print(f"largest difference over the window after the retune: {max(gaps):.2e} %")
    assert max(gaps) < 1e-3  # the two solves stop at the solver's tolerance, warm-started apart


@pytest.mark.timeout(60)
def test_a_new_r_restarts_the_arrival_cost_at_its_mean():
    y, s, _ = sequence()
    mhe = estimator()
    for k in range(80):
        mhe.update(y[k], s[k])
    mean = mhe.arrival.mean.copy()
    mhe.retune(dataclasses.replace(config(), r_diag_pct2=(4.0, 9.0), arrival_inflation=1.5,
                                   arrival_floor_pct2=(0.1, 0.2),
                                   solver=SolverSettings(eps_abs=1e-8, max_iter=50)))
    assert mhe.arrival.covariance == pytest.approx(np.diag([4.0, 9.0]))
    assert mhe.arrival.mean == pytest.approx(mean)
    assert (mhe.arrival.inflation, list(mhe.arrival.floor_variance)) == (1.5, [0.1, 0.2])
    assert (mhe.solver.settings.eps_abs, mhe.solver.settings.max_iter) == (1e-8, 50)
    assert mhe.update(y[80], s[80]).status is SolveStatus.SOLVED


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("change", "reason"), [
    ({"horizon": 60}, "horizon shapes the estimator's QP"),
    ({"arrival_centre": "previous_window"}, "arrival_centre shapes the estimator's QP"),
    ({"q_diag": (1.0,) * 6}, "Q changes at run time only by a factor common to every channel"),
    ({"r_diag_pct2": (1.0,) * (FAULTS + 1)}, "r_diag_pct2 needs one entry per fault"),
])
def test_what_cannot_change_at_run_time_is_refused_and_changes_nothing(change, reason):
    y, s, _ = sequence()
    mhe, untouched = estimator(), estimator()
    for k in range(60):
        mhe.update(y[k], s[k])
        untouched.update(y[k], s[k])
    with pytest.raises(ValueError, match=reason):
        mhe.retune(dataclasses.replace(config(), **change))
    assert mhe.update(y[60], s[60]).window_pct == pytest.approx(
        untouched.update(y[60], s[60]).window_pct, abs=1e-12)
