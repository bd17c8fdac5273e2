"""The arrival cost is exact in the linear-Gaussian case: with Gaussian random-walk faults
and no active constraint the moving-horizon estimate of the newest point is the
full-information (Kalman filter) estimate at every step."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uav_fault_estimator.estimation.arrival_cost import ArrivalCost, increment_prior
from uav_fault_estimator.estimation.estimator_config import (
    EstimatorConfig,
    FaultConfig,
    SolverSettings,
)
from uav_fault_estimator.estimation.fault_models import Monotonic, RandomWalk
from uav_fault_estimator.estimation.mhe import MovingHorizonEstimator

HORIZON, CHANNELS, UPDATES = 8, 6, 60
SIGMAS = (0.3, 0.2, 0.5)
COEFFICIENTS = (1.0, 0.95, 1.0)
Q_DIAG = (0.04, 0.04, 0.09, 0.01, 0.01, 0.01)
PRIOR_PCT, R_PCT2 = (1.0, -2.0, 0.5), (4.0, 1.0, 9.0)


def kalman_filter(samples) -> list[np.ndarray]:
    """Full-information estimates of the newest point: a Kalman filter from the prior at the
    initial window's first point, HORIZON - 1 samples before the first one."""
    a, variance = np.array(COEFFICIENTS), np.array(SIGMAS) ** 2
    mean, covariance = np.array(PRIOR_PCT), np.diag(R_PCT2)
    for _ in range(HORIZON - 1):
        mean, covariance = a * mean, a[:, None] * covariance * a + np.diag(variance)
    estimates = []
    for y, s, valid in samples:
        mean, covariance = a * mean, a[:, None] * covariance * a + np.diag(variance)
        rows = np.flatnonzero(valid)
        s_rows = s[rows]
        innovation = s_rows @ covariance @ s_rows.T + np.diag(np.array(Q_DIAG)[rows])
        gain = covariance @ s_rows.T @ np.linalg.inv(innovation)
        mean = mean + gain @ (y[rows] - s_rows @ mean)
        covariance = covariance - gain @ s_rows @ covariance
        estimates.append(mean)
    return estimates


@pytest.mark.timeout(60)
def test_moving_horizon_equals_full_information_with_gaussian_random_walks():
    rng = np.random.default_rng(3)
    faults = [FaultConfig(f"f{k}", "random_walk", {"sigma": sigma, "coefficient": a},
                          prior_pct=prior)
              for k, (sigma, a, prior) in enumerate(zip(SIGMAS, COEFFICIENTS, PRIOR_PCT,
                                                         strict=True))]
    estimator = MovingHorizonEstimator(EstimatorConfig(
        horizon=HORIZON, q_diag=Q_DIAG, r_diag_pct2=R_PCT2, faults=faults,
        solver=SolverSettings(eps_abs=1e-11, max_iter=100)))
    truth = np.zeros(len(SIGMAS))
    samples = []
    for _ in range(UPDATES):
        truth = np.array(COEFFICIENTS) * truth + rng.normal(scale=SIGMAS)
        s = rng.normal(size=(CHANNELS, len(SIGMAS)))
        y = s @ truth + rng.normal(scale=np.sqrt(Q_DIAG))
        valid = rng.random(CHANNELS) > 0.2
        valid[0] = True
        samples.append((y, s, valid))
    reference = kalman_filter(samples)
    deviations = []
    for (y, s, valid), expected in zip(samples, reference, strict=True):
        result = estimator.update(y, s, valid)
        deviations.append(np.abs(result.fault_pct - expected).max())
    print(f"largest |MHE - Kalman filter| over {UPDATES} updates (N = {HORIZON}): "
          f"{max(deviations):.2e} %")
    assert max(deviations) < 1e-8


def test_the_increment_priors_of_the_fault_models():
    """Mode and second moment about it: Gaussian exact; monotonic 0 and 2 lambda^2."""
    mode, moment = increment_prior(RandomWalk(0.3).increment_terms())
    assert mode == pytest.approx(0.0, abs=1e-9) and moment == pytest.approx(0.09)
    mode, moment = increment_prior(Monotonic(0.5).increment_terms())
    assert mode == pytest.approx(0.0, abs=1e-9) and moment == pytest.approx(0.5)


def test_floor_and_inflation():
    arrival = ArrivalCost(np.ones(2), np.zeros(2), np.zeros(2), np.zeros(2), np.eye(2) * 1e-4,
                          inflation=2.0, floor_variance=np.array([0.5, 0.0]))
    arrival.predict()
    assert np.diag(arrival.covariance) == pytest.approx([0.5, 2e-4])
    with pytest.raises(ValueError, match="inflation must be at least 1"):
        ArrivalCost(np.ones(1), np.zeros(1), np.zeros(1), np.zeros(1), np.eye(1), 0.5)
    assert math.isfinite(arrival.information.sum())
