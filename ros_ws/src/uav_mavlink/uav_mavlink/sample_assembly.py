"""An autopilot's readings (autopilot_messages) sampled onto the chain's grid of its own clock.

Each stream holds its latest reading (zero-order hold) until the next one. The grid is the
autopilot's boot time in steps of period_s: a timed reading at t releases every grid point
before t, each sampled from what the streams held then; a stream whose reading is older than
its maximum age at a grid point is missing there (NaN), as a lost sensor is in the
simulator, so that the estimator holds rather than use stale values.

Time: a reading carries the autopilot's boot time (ATTITUDE, GLOBAL_POSITION_INT,
LOCAL_POSITION_NED), a wrapping uint32 of it (SERVO_OUTPUT_RAW, unwrapped about the latest
boot time), or none (VFR_HUD, NAV_CONTROLLER_OUTPUT, WIND: stamped with the latest boot time
seen; dropped before the first timed reading). A timed reading more than REBOOT_STEP_S
before the latest one means the autopilot rebooted: everything held is forgotten and the
grid starts again from it (`Assembled.rebooted`); a smaller step back is a reading out of
order, dropped and counted.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from uav_common.channels import SETPOINT_FIELDS, STATE_CHANNELS

from uav_mavlink.autopilot_messages import (
    AIRSPEED,
    ATTITUDE,
    ENGINE,
    OUTPUTS,
    POSITION,
    SERVO_OUTPUTS,
    SETPOINTS,
    STREAMS,
    UINT32_US_S,
    VELOCITY,
    WIND,
    Reading,
)

# A timed reading this far behind the latest is a reboot, not a packet out of order [s].
REBOOT_STEP_S = 1.0
# After a silence longer than this the grid jumps to the next reading instead of filling
# the gap with missing samples [s] (a link down for minutes is not ten thousand samples).
MAX_FILL_S = 5.0
# Where a stream's channels go in a Sample.
_STATE_INDEX = {name: index for index, name in enumerate(STATE_CHANNELS)}


@dataclass(frozen=True)
class Sample:
    """The autopilot's values at one grid point of its boot time [s]: state (STATE_CHANNELS;
    fuel mass the given constant, NaN where a stream is missing), airspeed [m/s], the raw
    outputs 1..16 [us], setpoints (SETPOINT_FIELDS; the vertical velocity NaN: no autopilot
    streams it), the wind NED [m/s], and the streams missing at it."""

    boot_time_s: float
    state: np.ndarray
    airspeed_mps: float
    outputs_us: np.ndarray
    setpoints: np.ndarray
    wind_ned_mps: np.ndarray
    missing: tuple[str, ...]


@dataclass
class Assembled:
    """What one reading released: grid samples in time order, whether it revealed a
    reboot, and whether it was dropped (out of order, or untimed before any timed one)."""

    samples: list[Sample] = field(default_factory=list)
    rebooted: bool = False
    dropped: bool = False


class SampleAssembly:
    """Readings in, grid samples out (module docstring).

    period_s: the grid step [s]; max_age_s: each stream's longest hold [s] (a stream not
    named is never used); fuel_mass_kg: the state's fuel mass (no autopilot streams it);
    pitch_trim_rad: added to ATTITUDE's pitch (ArduPlane's trim it subtracted; 0 for PX4).
    """

    def __init__(self, period_s: float, max_age_s: Mapping[str, float], fuel_mass_kg: float,
                 pitch_trim_rad: float = 0.0) -> None:
        unknown = sorted(set(max_age_s) - set(STREAMS))
        if unknown or not period_s > 0:
            raise ValueError(f"period {period_s} s, unknown streams {unknown}")
        self.period_s = period_s
        self.max_age_s = dict(max_age_s)
        self.fuel_mass_kg = fuel_mass_kg
        self.pitch_trim_rad = pitch_trim_rad
        self.out_of_order = 0
        self._reset()

    def _reset(self) -> None:
        self.latest_boot_s: float | None = None
        self.held: dict[str, tuple[float, dict[str, float]]] = {}
        self.next_grid_index: int | None = None

    def add(self, reading: Reading) -> Assembled:
        """Take one reading; the grid samples it releases."""
        result = Assembled()
        time_s = self._time_of(reading)
        if time_s is None:
            result.dropped = True
            return result
        if reading.boot_time_s is not None:
            latest = self.latest_boot_s
            if latest is not None and time_s < latest - REBOOT_STEP_S:
                self._reset()
                result.rebooted = True
            elif latest is not None and time_s < latest:
                self.out_of_order += 1
                result.dropped = True
                return result
            result.samples = self._release_before(time_s)
            self.latest_boot_s = time_s
        self.held[reading.stream] = (time_s, self._corrected(reading).values)
        return result

    def _time_of(self, reading: Reading) -> float | None:
        if reading.boot_time_s is not None:
            return reading.boot_time_s
        if self.latest_boot_s is None:
            return None
        if reading.wrapped_boot_time_s is None:
            return self.latest_boot_s
        # the wrapped time nearest the latest boot time
        wraps = round((self.latest_boot_s - reading.wrapped_boot_time_s) / UINT32_US_S)
        return reading.wrapped_boot_time_s + wraps * UINT32_US_S

    def _corrected(self, reading: Reading) -> Reading:
        if reading.stream != ATTITUDE or not self.pitch_trim_rad:
            return reading
        values = dict(reading.values, pitch=reading.values["pitch"] + self.pitch_trim_rad)
        return Reading(reading.stream, reading.boot_time_s, values)

    def _release_before(self, time_s: float) -> list[Sample]:
        """The grid points before time_s not yet released; the first one at the first
        timed reading, and after a silence longer than MAX_FILL_S the one before time_s."""
        index = self.next_grid_index
        last = math.ceil(time_s / self.period_s - 1e-9) - 1  # the last grid point < time_s
        if index is None or (last - index) * self.period_s > MAX_FILL_S:
            index = last + 1 if index is None else last
        samples = [self._sample(k * self.period_s) for k in range(index, last + 1)]
        self.next_grid_index = max(index, last + 1)
        return samples

    def _fresh(self, stream: str, time_s: float) -> dict[str, float] | None:
        held = self.held.get(stream)
        if held is None or stream not in self.max_age_s:
            return None
        held_time_s, values = held
        return values if time_s - held_time_s <= self.max_age_s[stream] else None

    def _sample(self, time_s: float) -> Sample:
        state = np.full(len(STATE_CHANNELS), math.nan)
        state[_STATE_INDEX["fuel_mass"]] = self.fuel_mass_kg
        missing = []
        fresh = {}
        for stream in self.max_age_s:
            values = self._fresh(stream, time_s)
            if values is None:
                missing.append(stream)
            else:
                fresh[stream] = values
        # the velocity stream (LOCAL_POSITION_NED) where fresh, else the position's
        for stream in (POSITION, VELOCITY, ATTITUDE, ENGINE):
            for name, value in fresh.get(stream, {}).items():
                state[_STATE_INDEX[name]] = value
        outputs = fresh.get(OUTPUTS, {})
        setpoints = fresh.get(SETPOINTS, {})
        wind = fresh.get(WIND, {})
        return Sample(
            boot_time_s=time_s,
            state=state,
            airspeed_mps=fresh.get(AIRSPEED, {}).get("airspeed", math.nan),
            outputs_us=np.array([outputs.get(f"output_{n}", math.nan)
                                 for n in range(1, SERVO_OUTPUTS + 1)]),
            setpoints=np.array([setpoints.get(name, math.nan) for name in SETPOINT_FIELDS]),
            wind_ned_mps=np.array([wind.get(axis, math.nan)
                                   for axis in ("north", "east", "down")]),
            missing=tuple(missing),
        )
