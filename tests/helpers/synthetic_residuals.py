"""A synthetic residual sequence with known faults, and the estimator the unit tests fit it
with: the tests of the moving-horizon estimator's behaviour share them."""

from __future__ import annotations

import numpy as np
from uav_fault_estimator.estimation.estimator_config import EstimatorConfig, FaultConfig
from uav_fault_estimator.estimation.mhe import MovingHorizonEstimator

NOISE_SD = np.array([0.05, 0.05, 0.05, 0.01, 0.01, 0.01])
SAMPLES, FAULTS = 120, 2


def sequence(seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """y (T, 6), S (T, 6, 2) and the seeded f (T, 2): a lift-loss ramp and a drag step."""
    rng = np.random.default_rng(seed)
    t = np.arange(SAMPLES)
    s = np.array([[-0.006, -0.0035], [0.0, 0.0], [0.05, 0.0],
                  [0.65, 0.0], [0.01, 0.004], [-0.045, 0.021]])
    s = s * (1 + 0.1 * np.sin(t / 15.0))[:, None, None]
    f = np.stack([np.clip((t - 20) / 40, 0, 1) * 10.0, np.where(t >= 70, 20.0, 0.0)], axis=1)
    y = np.einsum("tmp,tp->tm", s, f) + NOISE_SD * rng.normal(size=(SAMPLES, 6))
    return y, s, f


def config(noise_variance_factor: float = 1.0) -> EstimatorConfig:
    """Two monotonic faults, N = 50, Q the noise's variances times the factor."""
    return EstimatorConfig(
        horizon=50, q_diag=tuple(noise_variance_factor * NOISE_SD**2),
        r_diag_pct2=(1.0,) * FAULTS,
        faults=[FaultConfig(f"fault_{k}", "monotonic", {"lambda_pct": 0.5}, lower_pct=0.0)
                for k in range(FAULTS)],
    )


def estimator(noise_variance_factor: float = 1.0) -> MovingHorizonEstimator:
    return MovingHorizonEstimator(config(noise_variance_factor))
