"""A stream's values at grid points, from its two neighbouring samples (no ROS here).

The one home of the sampling rule that the log path (uav_fault_estimator.flight_logs.resample,
whose docstring says why it suits which stream) and the MAVLink link
(uav_mavlink.sample_assembly) both follow. Each grid point t takes the stream's last sample
at or before it and its first at or after it (a sample within
uav_common.sample_grid.GRID_TOLERANCE_S of t counts as at t: stamps rounded to the
microsecond), and is

- LINEAR: interpolated linearly between them (the one sample's value on a sample);
- ANGULAR: the same for angles [rad], the short way round, into (-pi, pi];
- HOLD: the earlier one's value (zero-order hold);

and missing (NaN) before the first sample, after the last one (nothing is extrapolated) and
where its two neighbours lie further apart than the stream's longest gap: GAP_FACTOR times
its median period, unless a caller knows better.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from uav_common.sample_grid import GRID_TOLERANCE_S

# Samples further apart than this many median periods are a gap (a dropout), not jitter:
# logged intervals of a healthy stream vary by tens of percent, a lost sample doubles one.
GAP_FACTOR = 2.5
LINEAR, ANGULAR, HOLD = "linear", "angular", "hold"
METHODS = (LINEAR, ANGULAR, HOLD)


def wrap_rad(angle_rad: np.ndarray) -> np.ndarray:
    """Angles [rad] into (-pi, pi]; those already in it unchanged to the last bit."""
    return angle_rad - 2.0 * np.pi * np.ceil((angle_rad - np.pi) / (2.0 * np.pi))


def neighbours(times_s: np.ndarray, grid_s: np.ndarray,
               gap_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For every grid point of grid_s (K,) [s], in samples at times_s (n,) [s, ascending,
    n > 0]: the index of the last sample at or before it, of the first at or after it (the
    same index for a grid point on a sample), and whether both exist and lie at most gap_s
    [s] apart (K,) bool. The indices are clipped into range where that is False."""
    left = np.searchsorted(times_s, grid_s + GRID_TOLERANCE_S, side="right") - 1
    right = np.searchsorted(times_s, grid_s - GRID_TOLERANCE_S, side="left")
    inside = (left >= 0) & (right < times_s.size)
    left, right = np.clip(left, 0, None), np.clip(right, None, times_s.size - 1)
    valid = inside & (np.abs(times_s[right] - times_s[left]) <= gap_s)
    return left, right, valid


def interpolate(times_s: np.ndarray, values: np.ndarray, grid_s: np.ndarray, gap_s: float,
                methods: str | Sequence[str]) -> np.ndarray:
    """The samples values (n, k) at times_s (n,) [s, ascending] at the grid points grid_s
    (K,) [s] -> (K, k), each column by its method (one of METHODS for all, or one per
    column); NaN where the module's docstring says. ValueError for an unknown method."""
    columns = values.shape[1]
    per_column = [methods] * columns if isinstance(methods, str) else list(methods)
    unknown = sorted(set(per_column) - set(METHODS))
    if unknown or len(per_column) != columns:
        raise ValueError(f"resampling methods {per_column}: expected one of {METHODS} for "
                         f"each of {columns} columns")
    out = np.full((grid_s.size, columns), np.nan)
    if times_s.size == 0:
        return out
    left, right, valid = neighbours(times_s, grid_s, gap_s)
    start, end = values[left[valid]], values[right[valid]]
    span_s = times_s[right[valid]] - times_s[left[valid]]
    elapsed_s = grid_s[valid] - times_s[left[valid]]
    # 0 on a sample; clipped for a grid point within the tolerance before one
    weight = np.clip(np.divide(elapsed_s, span_s, out=np.zeros_like(span_s),
                               where=span_s > 0), 0.0, 1.0)[:, None]
    kinds = np.array(per_column)
    linear = start + weight * (end - start)
    angular = wrap_rad(start + weight * wrap_rad(end - start))
    out[valid] = np.where(kinds == HOLD, start, np.where(kinds == ANGULAR, angular, linear))
    return out
