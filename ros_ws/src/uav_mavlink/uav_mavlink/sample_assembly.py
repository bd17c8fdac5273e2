"""An autopilot's readings (autopilot_messages) sampled onto the chain's grid of its own clock.

The grid is the autopilot's boot time in steps of period_s. A stream is sampled there by the
log path's rule (uav_common.interpolation, which flight_logs.resample follows too):
interpolated linearly between its reading at or before the grid point and its first at or
after it (angles the short way round), missing (NaN) where the two lie further apart than
the stream's longest gap, before its first reading and after its last. The longest gap is,
as in the log path, GAP_FACTOR times the stream's median period, here over its last
PERIOD_WINDOW readings (a log's is over the whole log), and at most its max_age_s (all of
it before a second reading). A grid point is released once every stream it waits for has a
reading at or after it or is known to be missing there: the latest boot time seen lies past
the point and more than the stream's gap after its last reading (readings come in time
order, so neither a reading on the point, which gives its value whatever the gap, nor a
neighbour within the gap can come any more), or it has not been heard since the start.
So a sample goes out about one period of the slowest stream waited for after its grid point
(a stream lost delays it by its gap once).

HELD_STREAMS are not waited for: each holds its latest reading for its max_age_s. The
wind and the engine speed feed no detector input; the setpoints do, but ArduPlane sends them
at 2 Hz on its advised rates (NAV_CONTROLLER_OUTPUT, POSITION_TARGET_GLOBAL_INT), and
waiting for them there delayed samples by 0.28 s on average and 0.53 s at most, against
0.07 and 0.09 s held (ATTITUDE 25 Hz, position, outputs, VFR_HUD 10 Hz). On ALFA's 21
flights (setpoints at 20 Hz) held setpoints gave screen_logs' alarms on as many flights as
interpolated ones (9 against 7 with its /mavctrl/rpy attitude, 10 against 11 with imu/data's).

The body rates come from the fastest of ATTITUDE and the IMU streams (RAW_IMU or HIGHRES_IMU,
SCALED_IMU2), as the log reader keeps the faster of two topics giving one stream
(flight_logs.topics.LogStreams): speed is each stream's median period over its last
PERIOD_WINDOW readings; a tie keeps ATTITUDE's. Only the chosen one is waited for; where it
is missing the state takes ATTITUDE's. An IMU stream's max_age_s is ATTITUDE's unless given.

Time: a reading carries the autopilot's boot time (ATTITUDE, GLOBAL_POSITION_INT, ...), a
wrapping uint32 of it (SERVO_OUTPUT_RAW, unwrapped about the latest boot time), or none
(VFR_HUD, NAV_CONTROLLER_OUTPUT, WIND: stamped with the latest boot time seen; dropped
before the first timed reading). A timed reading more than REBOOT_STEP_S before the latest
one means the autopilot rebooted: every reading kept and the grid points not yet released
are forgotten and the grid starts again from it (`Assembled.rebooted`). A reading older than
its stream's previous one is out of order: dropped and counted. (Readings of different
streams may come a little out of order: the autopilot stamps some in ms, some in us.)
"""

from __future__ import annotations

import math
import statistics
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from uav_common.channels import SETPOINT_FIELDS, STATE_CHANNELS
from uav_common.interpolation import ANGULAR, GAP_FACTOR, LINEAR, interpolate, neighbours
from uav_common.sample_grid import GRID_TOLERANCE_S, NANOSECONDS_PER_SECOND

from uav_mavlink.autopilot_messages import (
    AIRSPEED,
    ATTITUDE,
    ENGINE,
    OUTPUTS,
    POSITION,
    RATES,
    RATES_2,
    SERVO_OUTPUTS,
    SETPOINTS,
    STREAMS,
    UINT32_US_S,
    VELOCITY,
    VELOCITY_SETPOINT,
    WIND,
    Reading,
)

# A timed reading this far behind the latest is a reboot, not a packet out of order [s].
REBOOT_STEP_S = 1.0
# After a silence longer than this the grid jumps to the next reading instead of filling
# the gap with missing samples [s] (a link down for minutes is not ten thousand samples).
MAX_FILL_S = 5.0
# Streams held, not waited for (the module's docstring says why).
HELD_STREAMS = (SETPOINTS, VELOCITY_SETPOINT, WIND, ENGINE)
# The body rates' sources, a tie kept by the first.
RATE_SOURCES = (ATTITUDE, RATES, RATES_2)
# The mavlink_node parameter that sets each stream's max_age_s (the IMU streams take
# ATTITUDE's; the held streams are held that long).
MAX_AGE_PARAMETERS = {
    ATTITUDE: "attitude_max_age_s", RATES: "attitude_max_age_s",
    RATES_2: "attitude_max_age_s", POSITION: "position_max_age_s",
    VELOCITY: "position_max_age_s", AIRSPEED: "air_data_max_age_s",
    OUTPUTS: "outputs_max_age_s", SETPOINTS: "slow_max_age_s",
    VELOCITY_SETPOINT: "slow_max_age_s", WIND: "slow_max_age_s", ENGINE: "slow_max_age_s"}
# Readings over which a stream's median period is measured.
PERIOD_WINDOW = 15
# Channels that are angles [rad] (interpolated the short way round).
ANGLES = frozenset(("roll", "pitch", "yaw", "roll_rad", "pitch_rad"))
# Where a stream's channels go in a Sample.
_STATE_INDEX = {name: index for index, name in enumerate(STATE_CHANNELS)}


def ros_offset_ns(ros_now_ns: int, boot_ns: int) -> int:
    """What maps the autopilot's boot time to ROS time (ROS = boot + offset) [ns], taken when
    a sample of boot time boot_ns [ns] is published at ROS time ros_now_ns [ns]: their
    difference rounded to whole seconds, so that a grid point of boot time that is a
    multiple of a period dividing a second (the detector's 0.2 s) is one in ROS time too:
    detector_node and residual_node take only the samples on their grid."""
    return round((ros_now_ns - boot_ns) / NANOSECONDS_PER_SECOND) * NANOSECONDS_PER_SECOND


@dataclass(frozen=True)
class Sample:
    """The autopilot's values at one grid point of its boot time [s]: state (STATE_CHANNELS;
    fuel mass the given constant, NaN where a stream is missing), airspeed [m/s], the raw
    outputs 1..16 [us], setpoints (SETPOINT_FIELDS: the commanded roll and pitch of
    NAV_CONTROLLER_OUTPUT, the commanded vertical velocity of POSITION_TARGET_GLOBAL_INT;
    NaN where missing), the wind NED [m/s], and the streams missing at it."""

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


@dataclass
class _Readings:
    """One stream's readings kept: times [s] ascending, channel names, values rows, and its
    recent intervals [s] (for its median period)."""

    names: tuple[str, ...]
    times_s: list[float] = field(default_factory=list)
    rows: list[list[float]] = field(default_factory=list)
    intervals_s: deque[float] = field(default_factory=lambda: deque(maxlen=PERIOD_WINDOW))

    def median_period_s(self) -> float:
        """The median of the recent intervals [s]; infinite before two readings."""
        return statistics.median(self.intervals_s) if self.intervals_s else math.inf


class SampleAssembly:
    """Readings in, grid samples out (module docstring).

    period_s: the grid step [s]; max_age_s: each stream's longest gap between neighbouring
    readings at most, or for HELD_STREAMS its longest hold [s] (a stream not named is never used;
    RATES and RATES_2 take ATTITUDE's unless named); fuel_mass_kg: the state's fuel mass (no
    autopilot streams it); pitch_trim_rad: added to ATTITUDE's pitch (ArduPlane's trim it
    subtracted; 0 for PX4).
    """

    def __init__(self, period_s: float, max_age_s: Mapping[str, float], fuel_mass_kg: float,
                 pitch_trim_rad: float = 0.0) -> None:
        unknown = sorted(set(max_age_s) - set(STREAMS))
        if unknown or not period_s > 0:
            raise ValueError(f"period {period_s} s, unknown streams {unknown}")
        self.period_s = period_s
        imu_ages = ({RATES: max_age_s[ATTITUDE], RATES_2: max_age_s[ATTITUDE]}
                    if ATTITUDE in max_age_s else {})
        self.max_age_s = {**imu_ages, **max_age_s}
        self.fuel_mass_kg = fuel_mass_kg
        self.pitch_trim_rad = pitch_trim_rad
        self.out_of_order = 0
        self._reset()

    def _reset(self) -> None:
        self.latest_boot_s: float | None = None
        self.kept: dict[str, _Readings] = {}
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
            if self.latest_boot_s is None or time_s > self.latest_boot_s:
                self._advance_grid(time_s)
        if not self._keep(reading.stream, time_s, self._corrected(reading).values):
            return self._out_of_order(result)
        result.samples = self._release()
        return result

    def _out_of_order(self, result: Assembled) -> Assembled:
        self.out_of_order += 1
        result.dropped = True
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

    def _advance_grid(self, time_s: float) -> None:
        """A timed reading at time_s [s], the latest: the grid starts at the first point at or
        after it, and after a silence longer than MAX_FILL_S goes on from the last point
        before it."""
        last = math.ceil(time_s / self.period_s - 1e-9) - 1  # the last grid point < time_s
        index = self.next_grid_index
        if index is None:
            self.next_grid_index = last + 1
        elif (last - index) * self.period_s > MAX_FILL_S:
            self.next_grid_index = last
        self.latest_boot_s = time_s

    def _keep(self, stream: str, time_s: float, values: dict[str, float]) -> bool:
        """The reading kept (one of the same time replaced); False for one older than the
        stream's latest."""
        kept = self.kept.setdefault(stream, _Readings(tuple(values)))
        if kept.times_s and time_s < kept.times_s[-1]:
            return False
        row = [values[name] for name in kept.names]
        if kept.times_s and time_s == kept.times_s[-1]:
            kept.rows[-1] = row
            return True
        if kept.times_s:
            kept.intervals_s.append(time_s - kept.times_s[-1])
        kept.times_s.append(time_s)
        kept.rows.append(row)
        return True

    def _rate_source(self) -> str:
        """The stream the body rates come from: the fastest of RATE_SOURCES heard."""
        heard = [s for s in RATE_SOURCES if s in self.kept and s in self.max_age_s]
        return min(heard, key=lambda s: self.kept[s].median_period_s(), default=ATTITUDE)

    def _waited(self) -> list[str]:
        """The streams grid points wait for."""
        source = self._rate_source()
        return [s for s in self.max_age_s if s not in HELD_STREAMS
                and (s not in RATE_SOURCES or s in (ATTITUDE, source))]

    def _gap_s(self, stream: str) -> float:
        """The stream's longest gap between neighbouring readings [s] (module docstring)."""
        return min(self.max_age_s[stream], GAP_FACTOR * self.kept[stream].median_period_s())

    def _settled(self, stream: str, time_s: float) -> bool:
        """Whether the stream's value at grid point time_s [s] is known: it has a reading
        at or after it, or is missing there whatever comes (the module's docstring)."""
        kept = self.kept.get(stream)
        if kept is None:
            return True
        last_s = kept.times_s[-1]
        return last_s >= time_s - GRID_TOLERANCE_S or (
            self.latest_boot_s > time_s + GRID_TOLERANCE_S
            and self.latest_boot_s - last_s > self._gap_s(stream))

    def _release(self) -> list[Sample]:
        """The grid points now settled for every stream waited for, in order."""
        samples = []
        while self.next_grid_index is not None:
            time_s = self.next_grid_index * self.period_s
            waited = self._waited()
            if time_s > self.latest_boot_s + GRID_TOLERANCE_S or not all(
                    self._settled(stream, time_s) for stream in waited):
                break
            samples.append(self._sample(time_s, waited))
            self.next_grid_index += 1
        self._forget_before(self.next_grid_index * self.period_s)
        return samples

    def _forget_before(self, time_s: float) -> None:
        """Drop each stream's readings before its last one at or before time_s [s]."""
        for kept in self.kept.values():
            first = int(np.searchsorted(kept.times_s, time_s + GRID_TOLERANCE_S,
                                        side="right")) - 1
            if first > 0:
                del kept.times_s[:first], kept.rows[:first]

    def _value(self, stream: str, time_s: float) -> dict[str, float] | None:
        """The stream's values at grid point time_s [s]: held (HELD_STREAMS) or
        interpolated; None where it is missing."""
        kept = self.kept.get(stream)
        if kept is None:
            return None
        times_s, grid_s = np.array(kept.times_s), np.array([time_s])
        if stream in HELD_STREAMS:
            left = int(np.searchsorted(times_s, time_s + GRID_TOLERANCE_S, side="right")) - 1
            fresh = left >= 0 and time_s - times_s[left] <= self.max_age_s[stream]
            return dict(zip(kept.names, kept.rows[left], strict=True)) if fresh else None
        gap_s = self._gap_s(stream)
        if not neighbours(times_s, grid_s, gap_s)[2][0]:
            return None
        methods = [ANGULAR if name in ANGLES else LINEAR for name in kept.names]
        values = interpolate(times_s, np.array(kept.rows, dtype=float), grid_s, gap_s,
                             methods)[0]
        return dict(zip(kept.names, values.tolist(), strict=True))

    def _sample(self, time_s: float, waited: list[str]) -> Sample:
        state = np.full(len(STATE_CHANNELS), math.nan)
        state[_STATE_INDEX["fuel_mass"]] = self.fuel_mass_kg
        used = [*waited, *(s for s in HELD_STREAMS if s in self.max_age_s)]
        values = {stream: self._value(stream, time_s) for stream in used}
        missing = tuple(stream for stream in used if values[stream] is None)
        fresh = {stream: value for stream, value in values.items() if value is not None}
        # the velocity stream (LOCAL_POSITION_NED) where fresh, else the position's; the
        # chosen IMU's body rates where fresh, else the attitude's
        for stream in (POSITION, VELOCITY, ATTITUDE, RATES, RATES_2, ENGINE):
            for name, value in fresh.get(stream, {}).items():
                state[_STATE_INDEX[name]] = value
        outputs = fresh.get(OUTPUTS, {})
        setpoints = {**fresh.get(SETPOINTS, {}), **fresh.get(VELOCITY_SETPOINT, {})}
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
            missing=missing,
        )
