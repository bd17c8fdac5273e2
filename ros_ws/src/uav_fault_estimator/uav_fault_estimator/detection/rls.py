"""Recursive least squares with exponential forgetting (Blanke & Hansen, eq. 9-11).

Model y[k] = phi[k]ᵀ theta + e[k] (eq. 5). Per sample: the prediction error
eps = y - phiᵀ theta[k-1] (eq. 9), then P and theta (eq. 10-11). Eq. 10 is written with an
inverse; the update below is the same matrix by the matrix inversion lemma, with no
inverse of P: P[k] = (P - K phiᵀ P) / lambda_f, K = P phi / (lambda_f + phiᵀ P phi).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RlsUpdate:
    """One step: the prediction error eps (eq. 9) made with the parameters before the step."""

    prediction_error: float
    theta: np.ndarray


class RecursiveLeastSquares:
    """theta (n,) and its covariance P (n, n), from initial values, with forgetting
    factor lambda_f in (0, 1] (1: no forgetting; memory about 1 / (1 - lambda_f) samples)."""

    def __init__(self, theta0: np.ndarray, p0: np.ndarray, forgetting: float) -> None:
        if not 0.0 < forgetting <= 1.0:
            raise ValueError(f"forgetting factor must be in (0, 1], got {forgetting}")
        self.theta = np.array(theta0, dtype=float)
        self.p = np.array(p0, dtype=float)
        if self.p.shape != (self.theta.size, self.theta.size):
            raise ValueError(f"P0 must be {self.theta.size}x{self.theta.size}")
        self.forgetting = forgetting

    def predict(self, phi: np.ndarray) -> float:
        """phiᵀ theta: the model's output with the current parameters."""
        return float(phi @ self.theta)

    def update(self, phi: np.ndarray, y: float) -> RlsUpdate:
        """Eq. 9-11 for one sample (phi (n,), y)."""
        eps = y - self.predict(phi)
        p_phi = self.p @ phi
        gain = p_phi / (self.forgetting + phi @ p_phi)
        self.theta = self.theta + gain * eps
        self.p = (self.p - np.outer(gain, p_phi)) / self.forgetting
        self.p = 0.5 * (self.p + self.p.T)  # keep it symmetric against rounding
        return RlsUpdate(float(eps), self.theta.copy())
