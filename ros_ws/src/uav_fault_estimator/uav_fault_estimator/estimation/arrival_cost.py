"""The moving-horizon estimator's arrival cost from the data that left its window.

UAV eq. 17 / EF eq. 26 summarise everything before the window by a quadratic prior on the
window's first point, ½ (f(0) - c)ᵀ Π⁻¹ (f(0) - c). Here Π and c come from a Kalman filter
that lags the window by N samples, the filtering arrival cost of the MHE literature (Rao,
Rawlings & Mayne, 2003): each update it absorbs the residual sample that just left the
window (eq. 18's data term for that sample) and predicts through the fault model's increment
(EF eq. 3) to the new first point. Not the marginal of the previous window's posterior,
which would count the samples still in the window twice. For Gaussian random walks without
active constraints this makes the moving-horizon estimate equal to the full-information one.

Non-Gaussian increments (monotonic, uniform, Laplacian: EF section III) enter the filter as a
Gaussian centred on the increment's most probable value (the MAP estimator's own choice)
with the increment's second moment about it: exact for Gaussian increments. A covariance
floor and an inflation keep the prior from hardening against faults that do change.
No ROS here.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

from uav_fault_estimator.estimation.fault_models import IncrementTerms


def increment_prior(terms: IncrementTerms) -> tuple[float, float]:
    """The most probable increment and the second moment about it of the increment density
    ∝ exp(-(½ w δ² + c δ + b |δ|)) on [lower, upper] (fault_models' IncrementTerms)."""
    lower, upper = terms.lower_pct, terms.upper_pct
    if lower == upper:
        return lower, 0.0
    w, c, b = terms.quadratic_weight, terms.linear_cost, terms.abs_cost

    def cost(delta: float) -> float:
        return 0.5 * w * delta * delta + c * delta + b * abs(delta)

    if w == c == b == 0.0:  # uniform on a bounded range
        return 0.5 * (lower + upper), (upper - lower) ** 2 / 12.0
    # Where the density has fallen by e^-60 at the most (convex cost): the search range.
    reach = 60.0 * max(1.0 / math.sqrt(w) if w > 0 else 0.0,
                       1.0 / (abs(c) + b) if abs(c) + b > 0 else 0.0)
    low, high = max(lower, -reach), min(upper, reach)
    mode = float(minimize_scalar(cost, bounds=(low, high), method="bounded",
                                 options={"xatol": 1e-12}).x)
    mode = min(max(mode, low), high)
    least = cost(mode)

    def density(delta: float) -> float:
        return math.exp(least - cost(delta))

    kinks = sorted({low, high, mode, *([0.0] if low < 0.0 < high else [])})
    pieces = list(itertools.pairwise(kinks))
    mass = sum(quad(density, a, z)[0] for a, z in pieces)
    moment = sum(quad(lambda d: (d - mode) ** 2 * density(d), a, z)[0] for a, z in pieces)
    return mode, moment / mass


class ArrivalCost:
    """Gaussian summary N(mean, information⁻¹) of the window's first point given the data
    before the window: `absorb` a sample leaving the window, then `predict` one step.

    Kept in information form: absorbing a sample adds its data term (SᵀWS, SᵀWy: the
    window's own stage_normal_equations of it, not recomputed) and the window's QP takes
    the information as it is; the prediction is the one step that needs the covariance.
    Inputs: coefficients (p,) a of f(t+1) = a f(t) + gamma; increment_mode (p,) and
    increment_variance (p,) of gamma (increment_prior); mean (p,) and covariance (p, p) before
    any data (positive definite); inflation >= 1 multiplies the covariance every step;
    floor_variance (p,) is the least variance each fault's prior keeps.
    """

    def __init__(self, coefficients: np.ndarray, increment_mode: np.ndarray,
                 increment_variance: np.ndarray, mean: np.ndarray, covariance: np.ndarray,
                 inflation: float = 1.0, floor_variance: np.ndarray | None = None) -> None:
        if not inflation >= 1.0:
            raise ValueError(f"arrival cost inflation must be at least 1, got {inflation}")
        self.coefficients = np.asarray(coefficients, dtype=float)
        self.increment_mode = np.asarray(increment_mode, dtype=float)
        self.increment_variance = np.diag(np.asarray(increment_variance, dtype=float))
        self.mean = np.array(mean, dtype=float)
        self.information = np.linalg.inv(np.asarray(covariance, dtype=float))
        self.inflation = inflation
        self.floor_variance = (np.zeros(self.mean.size) if floor_variance is None
                               else np.asarray(floor_variance, dtype=float))
        self._diagonal = np.diag_indices(self.mean.size)

    def absorb(self, gram: np.ndarray, linear: np.ndarray) -> None:
        """Measurement update with one residual sample's data term: gram SᵀWS (p, p) [1/%²]
        and linear SᵀWy (p,) [1/%] (qp_problem.stage_normal_equations; W = 0 on channels
        left out)."""
        if not gram.any():
            return
        vector = self.information @ self.mean + linear
        self.information = self.information + gram
        self.mean = np.linalg.solve(self.information, vector)

    def predict(self) -> None:
        """Through one increment: mean a f + mode, covariance a P a + variance, inflated,
        floored."""
        a = self.coefficients
        self.mean = a * self.mean + self.increment_mode
        covariance = (a[:, None] * self.covariance * a + self.increment_variance) * self.inflation
        covariance[self._diagonal] = np.maximum(covariance[self._diagonal], self.floor_variance)
        self.information = np.linalg.inv(covariance)
        self.information = 0.5 * (self.information + self.information.T)

    @property
    def covariance(self) -> np.ndarray:
        """Π (p, p) [%²]: the arrival cost's covariance."""
        return np.linalg.inv(self.information)
