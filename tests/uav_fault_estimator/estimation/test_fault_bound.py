"""The Cramer-Rao bound of the faults over a window, against what can be worked by hand."""

from __future__ import annotations

import numpy as np
import pytest
from uav_fault_estimator.estimation.fault_bound import pair_bounds, window_fault_bound


@pytest.mark.timeout(30)
def test_without_wind_errors_it_is_the_mean_of_white_samples():
    """One fault seen by one row with unit sensitivity: sigma / sqrt(N)."""
    bound = window_fault_bound(np.ones((25, 1, 1)), np.zeros((25, 1, 0)), np.array([4.0]),
                               0.2, 0.95)
    assert bound == pytest.approx([2.0 / 5.0])


@pytest.mark.timeout(30)
def test_a_wind_error_that_mimics_the_fault_widens_the_bound_as_its_prior_loosens():
    """A wind error with the fault's own signature leaves only its Gauss-Markov prior to
    tell the two apart: a constant fault is then told from a slowly wandering wind error
    only as far as the prior forbids the error to stay put."""
    n = 40
    fault, wind, noise = np.ones((n, 1, 1)), np.ones((n, 1, 1)), np.array([1.0])
    alone = window_fault_bound(fault, np.zeros((n, 1, 0)), noise, 0.1, 0.9)[0]
    tight = window_fault_bound(fault, wind, noise, 0.01, 0.9)[0]
    loose = window_fault_bound(fault, wind, noise, 1.0, 0.9)[0]
    assert alone < tight < loose
    # the exact value for the tight prior: noise plus the wind error's mean over the window
    lags = np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
    wind_covariance = 0.01**2 / (1 - 0.9**2) * 0.9**lags
    exact = np.sqrt(1.0 / np.sum(np.linalg.inv(np.eye(n) + wind_covariance)))
    assert tight == pytest.approx(exact)


@pytest.mark.timeout(30)
def test_two_faults_that_move_together_are_known_apart_and_not_together():
    """Two faults of unit variance, correlated 0.9 (what one unknown moves both by): their
    mean's variance is (1 + 1 + 1.8) / 4, their half difference's (1 + 1 - 1.8) / 4; a third
    fault does not enter."""
    covariance = np.array([[1.0, 0.9, 0.0], [0.9, 1.0, 0.0], [0.0, 0.0, 100.0]])
    mean, half_difference = pair_bounds(covariance, 0, 1)
    assert mean == pytest.approx(np.sqrt(0.95))
    assert half_difference == pytest.approx(np.sqrt(0.05))
