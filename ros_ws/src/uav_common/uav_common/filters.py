"""First-order low-pass filtering F(s) = 1/(tau s + 1), discretised exactly.

Used for the wind estimate (embedded-estimation paper, eq. 3-4) and for F_a (eq. 5-6).
The input is held constant over each sample interval (zero-order hold), which is exact for
the interval means the residual pipeline feeds it, so the discretisation adds no error of
its own.
"""

from __future__ import annotations

import math

import numpy as np


class LowPass:
    """y' = (u - y) / tau on arrays of any shape, with a variable sample interval.

    The first input initialises the output (no start-up transient from zero).
    """

    def __init__(self, tau_s: float) -> None:
        if not tau_s > 0:
            raise ValueError(f"filter time constant must be positive, got {tau_s}")
        self.tau_s = tau_s
        self.output: np.ndarray | None = None

    def reset(self) -> None:
        self.output = None

    def update(self, value: np.ndarray, dt_s: float) -> np.ndarray:
        """Filter one interval of length dt_s [s] over which the input was `value`."""
        if self.output is None:
            self.output = np.array(value, dtype=float)
        else:
            # Exact solution over the interval: y += (1 - exp(-dt/tau)) (u - y).
            self.output += -math.expm1(-dt_s / self.tau_s) * (value - self.output)
        return self.output


class SettlingLowPass(LowPass):
    """LowPass that starts as the running mean of its inputs: until tau_s of input, the
    output is their time-weighted mean, then the low-pass (whose start-up would otherwise
    carry the first input's error for several tau)."""

    def reset(self) -> None:
        super().reset()
        self.elapsed_s = 0.0

    def update(self, value: np.ndarray, dt_s: float) -> np.ndarray:
        if self.output is None:
            self.elapsed_s = dt_s
            return super().update(value, dt_s)
        self.elapsed_s += dt_s
        gain = max(dt_s / self.elapsed_s, -math.expm1(-dt_s / self.tau_s))
        self.output += gain * (value - self.output)
        return self.output
