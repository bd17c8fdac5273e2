"""Change detection on Laplacian residuals (Blanke & Hansen, section III.A-B).

- laplacian_glrt: the GLRT statistic for a change of the median of Laplacian samples,
  T_L = M log(b0 / b1) (eq. 20-22): b0 = mean |x| is the scale's maximum-likelihood estimate
  with the median fixed at 0 (H0), b1 = mean |x - median(x)| with the median estimated (H1).
  With those estimates each likelihood is (2 b)^-M exp(-M), so the log ratio is eq. 22.
- SlidingGlrt: T_L over the last M samples.
- SlidingMeanChange: the fast test's signed change, the mean of the last W residuals against
  the mean of the R before them, in units of its fault-free spread (the residuals those of the
  generator with its parameters fixed): a window test for a change of the mean, which
  nothing adapts away and a constant offset does not move.
- per_sample_probability: the per-sample exceedance probability that gives a stated rate of
  false alarms per flight hour for a window test.
- weibull_fit / weibull_threshold: the two-parameter Weibull distribution of a statistic
  under H0 (scipy's maximum-likelihood fit, location 0) and the threshold of eq. 25,
  gamma = v (-ln P_FA)^(1/beta), for which P(T > gamma | H0) = P_FA (eq. 23-24).
No ROS here.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np


def laplacian_glrt(samples: np.ndarray) -> float:
    """T_L of eq. 22 for the samples (M,); 0 for a window of zeros."""
    x = np.asarray(samples, dtype=float)
    scale_h0 = np.mean(np.abs(x))
    scale_h1 = np.mean(np.abs(x - np.median(x)))
    if scale_h1 <= 0.0:  # every sample equal: no spread to compare against
        return 0.0 if scale_h0 <= 0.0 else math.inf
    return float(x.size * math.log(scale_h0 / scale_h1))


class SlidingGlrt:
    """T_L over a sliding window of the last `window` samples (None until it is full)."""

    def __init__(self, window: int) -> None:
        if window < 2:
            raise ValueError(f"GLRT window must be at least 2 samples, got {window}")
        self.samples: deque[float] = deque(maxlen=window)

    def update(self, residual: float) -> float | None:
        self.samples.append(residual)
        if len(self.samples) < self.samples.maxlen:
            return None
        return laplacian_glrt(np.fromiter(self.samples, float))


class SlidingMeanChange:
    """The fast test's signed change: the mean of the last `window` residuals against the
    mean of the `reference` residuals before them, (m_W - m_R) / (std sqrt(1/W + 1/R)) (None
    until both are full): about N(0, 1) for white residuals of spread std whatever their
    mean (a new day's bias, trim or sensor offset moves both means alike), and a step d of
    the mean moves it by about d / std / sqrt(1/W + 1/R) within `window` samples. Its size
    is the test's statistic, its sign (over the channels) the change's signature."""

    def __init__(self, window: int, reference: int, std: float) -> None:
        if window < 1 or reference < 1 or not std > 0.0:
            raise ValueError(f"window test: window {window} and reference {reference} "
                             f"(>= 1 each), spread {std} (> 0)")
        self.samples: deque[float] = deque(maxlen=window + reference)
        self.window = window
        self.scale = std * math.sqrt(1.0 / window + 1.0 / reference)

    def update(self, residual: float) -> float | None:
        self.samples.append(residual)
        if len(self.samples) < self.samples.maxlen:
            return None
        values = np.fromiter(self.samples, float)
        reference, recent = values[:-self.window], values[-self.window:]
        return float(recent.mean() - reference.mean()) / self.scale


def per_sample_probability(false_alarms_per_hour: float, window: int,
                           sample_period_s: float) -> float:
    """The probability per sample that a window test's statistic exceeds its threshold for
    false_alarms_per_hour false alarms per flight hour: an exceedance lasts about a window
    (the statistics of overlapping windows share their samples), so an hour of
    3600 / sample_period_s samples holds about that many over window of them."""
    if not false_alarms_per_hour > 0.0:
        raise ValueError(f"false alarms per hour must be > 0, got {false_alarms_per_hour}")
    return min(false_alarms_per_hour * window * sample_period_s / 3600.0, 0.5)


@dataclass(frozen=True)
class Weibull:
    """Two-parameter Weibull distribution: scale v > 0, shape beta > 0 (location 0)."""

    scale: float
    shape: float

    def survival(self, value: float) -> float:
        """P(T > value) = exp(-(value / v)^beta) (eq. 24)."""
        return math.exp(-((max(value, 0.0) / self.scale) ** self.shape))


def weibull_fit(samples: np.ndarray) -> Weibull:
    """Maximum-likelihood Weibull of positive samples (scipy.stats.weibull_min, location 0);
    ValueError when fewer than 10 positive samples are given."""
    x = np.asarray(samples, dtype=float)
    x = x[np.isfinite(x) & (x > 0.0)]
    if x.size < 10:
        raise ValueError(f"a Weibull fit needs at least 10 positive samples, got {x.size}")
    # imported here: scipy.stats costs 0.7 s at import, and detector_node, which reads a
    # calibration and never fits one, would pay it at every start
    from scipy import stats

    shape, _, scale = stats.weibull_min.fit(x, floc=0.0)
    return Weibull(scale=float(scale), shape=float(shape))


def weibull_threshold(distribution: Weibull, false_alarm_probability: float) -> float:
    """gamma = v (-ln P_FA)^(1/beta) (eq. 25)."""
    if not 0.0 < false_alarm_probability < 1.0:
        raise ValueError(f"P_FA must be in (0, 1), got {false_alarm_probability}")
    return distribution.scale * (-math.log(false_alarm_probability)) ** (1.0 / distribution.shape)
