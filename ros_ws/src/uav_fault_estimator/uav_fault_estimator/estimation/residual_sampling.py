"""residual_node's sampling, without ROS: the residual generator on every sensor sample,
one residual sample out every update period of sim time.

The one home of the update grid for the residual node, the offline chain and the model
calibration: the first sample out is the first at or after a multiple of the period, then
the first at or after each next multiple (a stamp within uav_common.sample_grid's tolerance
of a multiple counts as on it), so a sample the generator refuses or a gap in the stream
moves that output to the next sample instead of losing it.
"""

from __future__ import annotations

import numpy as np
from uav_common.sample_grid import GRID_TOLERANCE_S, next_grid_time

from uav_fault_estimator.estimation.residuals import ResidualGenerator, ResidualSample


class ResidualSampler:
    """The generator (residuals.ResidualGenerator) and the update grid of period_s [s]."""

    def __init__(self, generator: ResidualGenerator, period_s: float) -> None:
        if not period_s > 0:
            raise ValueError(f"update period must be positive, got {period_s} s")
        self.generator, self.period_s = generator, period_s
        self.next_out_s: float | None = None
        self.newest: ResidualSample | None = None  # the generator's, due or not

    def reset(self) -> None:
        """A restarted source: the generator's filters and the grid from scratch."""
        self.generator.reset()
        self.next_out_s = None
        self.newest = None

    def update(self, time_s: float, state: np.ndarray, controls: np.ndarray,
               wind_ned_mps: np.ndarray, air_data: np.ndarray | None) -> ResidualSample | None:
        """One sensor sample into the generator (its inputs, ResidualGenerator.update; a
        ValueError for a sample it cannot evaluate, the grid unchanged); the residual sample
        when an output is due, else None. The generator's sample, due or not, is `newest`."""
        self.newest = None
        sample = self.newest = self.generator.update(time_s, state, controls, wind_ned_mps,
                                                     air_data)
        if sample is None:
            return None
        if self.next_out_s is None:
            self.next_out_s = next_grid_time(time_s, self.period_s, after=False)
        if time_s < self.next_out_s - GRID_TOLERANCE_S:
            return None
        self.next_out_s = next_grid_time(time_s, self.period_s, after=True)
        return sample
