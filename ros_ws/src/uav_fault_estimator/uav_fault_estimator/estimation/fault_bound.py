"""The Cramer-Rao bound of the faults over one window: what any unbiased estimator could do
with these residuals, their noise and the wind errors' Gauss-Markov model. No ROS here.

Over a window of N samples the residuals are, stacked, y = S_f f + B e + v (the linear
model of the estimator, UAV eq. 15 with the wind errors as unknowns): f (p,) constant
faults, e (N w,) the wind errors, a Gauss-Markov process per component
(e(t+1) = a e(t) + gamma, gamma ~ N(0, sigma^2): stationary covariance
sigma^2 / (1 - a^2) a^|i-j| between samples i and j), v the residual noise. The noise is
taken white with each row's variance over its AR(1) white share (noise_model.white_share):
the variance of a mean of correlated samples.
Marginalising e, y ~ N(S_f f, B P_e B^T + R), so the Fisher information of f is
J = S_f^T (B P_e B^T + R)^-1 S_f and every unbiased estimate has covariance >= J^-1.
"""

from __future__ import annotations

import numpy as np


def window_fault_covariance(fault_sensitivity: np.ndarray, wind_sensitivity: np.ndarray,
                            noise_variances: np.ndarray, wind_sigma_mps: float,
                            wind_coefficient: float) -> np.ndarray:
    """The Cramer-Rao covariance J^-1 of the constant faults over the window (p, p) [%^2].

    Inputs: fault_sensitivity (N, m, p) [residual unit / %] and wind_sensitivity (N, m, w)
    [residual unit per m/s] of the window's samples (w may be 0: no wind errors, or all
    zero where vanes measure the flow); noise_variances (m,) [residual unit^2], white;
    the wind errors' Gauss-Markov step wind_sigma_mps [m/s] and coefficient a in [0, 1).
    """
    samples, rows, winds = wind_sensitivity.shape
    covariance = np.diag(np.tile(noise_variances, samples))
    if winds:
        lags = np.abs(np.subtract.outer(np.arange(samples), np.arange(samples)))
        stationary = wind_sigma_mps**2 / (1.0 - wind_coefficient**2)
        wind_covariance = np.kron(stationary * wind_coefficient**lags, np.eye(winds))
        stacked = np.zeros((samples * rows, samples * winds))
        for k in range(samples):
            stacked[k * rows:(k + 1) * rows, k * winds:(k + 1) * winds] = wind_sensitivity[k]
        covariance += stacked @ wind_covariance @ stacked.T
    faults = fault_sensitivity.reshape(samples * rows, -1)
    information = faults.T @ np.linalg.solve(covariance, faults)
    return np.linalg.inv(information)


def window_fault_bound(fault_sensitivity: np.ndarray, wind_sensitivity: np.ndarray,
                       noise_variances: np.ndarray, wind_sigma_mps: float,
                       wind_coefficient: float) -> np.ndarray:
    """The Cramer-Rao deviation of each constant fault over the window (p,) [%]: the root of
    window_fault_covariance's diagonal (same inputs)."""
    return np.sqrt(np.diag(window_fault_covariance(
        fault_sensitivity, wind_sensitivity, noise_variances, wind_sigma_mps,
        wind_coefficient)))


def pair_bounds(covariance: np.ndarray, first: int, second: int) -> tuple[float, float]:
    """The deviation of the mean (f_first + f_second) / 2 and of the half difference
    (f_first - f_second) / 2 of two faults [%] under a fault covariance (p, p) [%^2]: for the
    two wings' faults of one kind, what moves them together (symmetric) and apart."""
    mean, half_difference = np.zeros(len(covariance)), np.zeros(len(covariance))
    mean[[first, second]] = 0.5
    half_difference[[first, second]] = 0.5, -0.5
    return (float(np.sqrt(mean @ covariance @ mean)),
            float(np.sqrt(half_difference @ covariance @ half_difference)))
