"""The sample grid: which simulation times are samples of a fixed period (no ROS here).

Stamps are simulation times rounded to the nanosecond, so a stamp on a grid of period
period_s lies within GRID_TOLERANCE_S of a whole multiple of it. The one home of that check
for the simulator's readers, the residual node, the detector and the recordings.
"""

from __future__ import annotations

import math

NANOSECONDS_PER_SECOND = 1_000_000_000  # stamps are integer nanoseconds
GRID_TOLERANCE_S = 1e-6  # far above nanosecond rounding, far below any sensor period


def on_grid(time_s: float, period_s: float) -> bool:
    """Whether time_s [s] is a whole multiple of period_s [s] (within GRID_TOLERANCE_S)."""
    return abs(time_s - round(time_s / period_s) * period_s) < GRID_TOLERANCE_S


def next_grid_time(time_s: float, period_s: float, after: bool) -> float:
    """The first multiple of period_s [s] at or after time_s (after=False), or strictly
    after it (after=True), a stamp within GRID_TOLERANCE_S of a multiple counting as on it."""
    tolerance = GRID_TOLERANCE_S / period_s
    if after:
        return (math.floor(time_s / period_s + tolerance) + 1) * period_s
    return math.ceil(time_s / period_s - tolerance) * period_s
