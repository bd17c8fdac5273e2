"""A grid sample of the autopilot (sample_assembly.Sample) as the streams sim_node publishes:
what mavlink_node sends on, and what the offline chain feeds its models when it flies
through the link.

- state: as sampled (the fuel mass the given constant);
- controls (CONTROL_CHANNELS): aileron, elevator, rudder and throttle through the airframe's
  servo mapping (uav_aircraft.airframe.control_values); flap 0 (none mapped: retracted),
  mixture and ignition 1 (the engine runs: an autopilot streams neither);
- air data (AIR_DATA_CHANNELS): the autopilot's airspeed; angle of attack and sideslip NaN
  (no vanes on the link);
- the wind: the autopilot's estimate through the embedded-estimation paper's filter (eq. 4),
  NaN while it is missing (the filter holds and goes on when it returns);
- setpoints as sampled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from uav_aircraft.airframe import CONTROLS, MAX_OUTPUTS, Airframe, control_values
from uav_common.channels import (
    AIR_DATA_CHANNELS,
    AIRSPEED_INDEX,
    CONTROL_CHANNELS,
    UNREPORTED_CONTROLS,
)
from uav_common.filters import LowPass

from uav_mavlink.sample_assembly import Sample

_CONTROL_INDEX = [CONTROL_CHANNELS.index(name) for name in CONTROLS]


@dataclass(frozen=True)
class Streams:
    """One sample's streams, in uav_common.channels orders; wind NED [m/s]."""

    state: np.ndarray
    controls: np.ndarray
    air_data: np.ndarray
    wind_filtered_ned_mps: np.ndarray
    setpoints: np.ndarray


class StreamConversion:
    """Grid samples, in time order, to Streams (module docstring)."""

    def __init__(self, airframe: Airframe, wind_filter_tau_s: float) -> None:
        self.airframe = airframe
        self.wind_filter = LowPass(wind_filter_tau_s)
        self.previous_s: float | None = None

    def reset(self) -> None:
        """A new flight (the autopilot rebooted): the wind filter starts again."""
        self.wind_filter.reset()
        self.previous_s = None

    def streams(self, sample: Sample) -> Streams:
        controls = np.full(len(CONTROL_CHANNELS), math.nan)
        controls[_CONTROL_INDEX] = control_values(
            self.airframe, lambda output: sample.outputs_us[None, output - 1],
            range(1, MAX_OUTPUTS + 1), 1)[0]
        for index, value in UNREPORTED_CONTROLS.items():
            controls[index] = value
        air_data = np.full(len(AIR_DATA_CHANNELS), math.nan)
        air_data[AIRSPEED_INDEX] = sample.airspeed_mps
        return Streams(sample.state, controls, air_data, self._filtered_wind(sample),
                       sample.setpoints)

    def _filtered_wind(self, sample: Sample) -> np.ndarray:
        dt_s = 0.0 if self.previous_s is None else sample.boot_time_s - self.previous_s
        self.previous_s = sample.boot_time_s
        if not np.isfinite(sample.wind_ned_mps).all():
            return np.full(3, math.nan)
        return self.wind_filter.update(sample.wind_ned_mps, dt_s).copy()
