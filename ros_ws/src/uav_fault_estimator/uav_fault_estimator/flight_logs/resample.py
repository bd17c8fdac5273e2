"""Asynchronous log streams onto the detector's sample grid.

The detector takes state and controls with one stamp, on whole multiples of its
calibration's sample_period_s (0.2 s); a log's streams come at their own rates and instants
(rates at 2.5-250 Hz, servo outputs at 3-50 Hz, airspeed at 10 Hz). Each grid point t takes
the stream's two neighbouring samples, the last at or before t and the first at or after it
(a sample within uav_common.sample_grid.GRID_TOLERANCE_S of t counts as at t: stamps rounded to
the microsecond), and (uav_common.interpolation: the rule the MAVLink link samples by too):

- every stream is interpolated linearly between them: body rates, attitude and airspeed
  are smooth on the scale of the sample intervals, linear interpolation is exact on a ramp,
  and it adds no overshoot or values the aircraft never had (as splines can). Angles go the
  short way round and stay in (-pi, pi] (yaw crosses +-pi).
- actuator commands (surfaces, throttle) too: an autopilot's output is piecewise constant
  only at its own rate (50-400 Hz); a log that keeps it at 3-10 Hz holds samples of a
  command that moves smoothly between them, and holding the last sample (zero-order hold)
  lags it by half a log period on average. Measured on the aileron loss written as a ULog
  and a MAVROS bag (outputs at 2.9 Hz; 5 seeds, 2 onsets, both formats): the first combined
  alarm came 0.05 s before the direct run's on average, within one 0.2 s sample in 18 of 20
  (at most 0.4 s off) interpolated, against 0.93 s before on average, within one sample in
  11 of 20 and up to 7.8 s off held. HOLD stays available to `resample`.

A grid point is missing (NaN), not invented, when it lies before a stream's first or after
its last sample (nothing is extrapolated) or when its neighbouring samples are further
apart than the stream's max gap: GAP_FACTOR times its median period by default. A stream
slower than the grid (median period above the grid period) is said in one line: most of its
grid points are then interpolated or held rather than measured.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from uav_aircraft.airframe import Airframe
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_common.interpolation import (
    ANGULAR,
    GAP_FACTOR,
    HOLD,
    LINEAR,
    METHODS,
    interpolate,
)
from uav_common.sample_grid import GRID_TOLERANCE_S

from uav_fault_estimator.detection.detector import DetectorFlight
from uav_fault_estimator.flight_logs.streams import (
    AIRSPEED,
    ATTITUDE,
    BODY_RATES,
    GROUND_VELOCITY,
    OUTPUTS,
    PITCH_SETPOINT,
    ROLL_SETPOINT,
    SURFACES,
    VELOCITY_SETPOINT,
    WIND,
    FlightLog,
    TimedSeries,
)
from uav_fault_estimator.flight_logs.surfaces import mixed_output_mismatches, surface_deflections


def grid_times_s(start_s: float, end_s: float, period_s: float) -> np.ndarray:
    """The whole multiples k * period_s [s] from start_s to end_s [s] (both included, within
    GRID_TOLERANCE_S), as the detector's on_grid() recognises them; empty when none."""
    tolerance = GRID_TOLERANCE_S / period_s
    first = math.ceil(start_s / period_s - tolerance)
    last = math.floor(end_s / period_s + tolerance)
    return np.arange(first, last + 1) * period_s


def max_gap_s(series: TimedSeries) -> float:
    """The longest interval [s] between two samples of series that is not a gap."""
    return GAP_FACTOR * series.median_period_s


def resample(series: TimedSeries, grid_s: np.ndarray, method: str,
             gap_s: float | None = None) -> np.ndarray:
    """Every column of series at the grid points grid_s (K,) [s] -> (K, k), by method
    (LINEAR, ANGULAR or HOLD: uav_common.interpolation, the rule the MAVLink link samples
    by too); NaN before the first and after the last sample and between neighbouring
    samples further apart than gap_s [s] (default max_gap_s(series))."""
    if method not in METHODS:
        raise ValueError(f"resampling method {method!r}: expected {LINEAR}, {ANGULAR} or {HOLD}")
    if series.times_s.size == 0:
        return np.full((grid_s.size, len(series.columns)), np.nan)
    return interpolate(series.times_s, series.values, grid_s,
                       max_gap_s(series) if gap_s is None else gap_s, method)


SLOW_MARGIN = 0.01  # relative: a median period this much above the grid's is still its rate


def slow_stream_warning(name: str, series: TimedSeries, period_s: float) -> str | None:
    """One line when the stream's median period is longer than the grid's period_s [s] by
    more than its timing jitter can make it (SLOW_MARGIN: a 5 Hz stream stamped to the
    microsecond is the grid's rate)."""
    stream_period_s = series.median_period_s
    if stream_period_s <= period_s * (1.0 + SLOW_MARGIN):
        return None
    return (f"stream {name} is slower than the detector's grid: a sample every "
            f"{stream_period_s:.3f} s ({1.0 / stream_period_s:.2f} Hz) against "
            f"{period_s:g} s; between its samples the grid points are estimated, not measured")


@dataclass(frozen=True)
class DetectorInputs:
    """A log on the detector's grid: times_s (K,) [s from the log's start], state (K, 14)
    and controls (K, 7) in uav_common.channels order (NaN where the log has no such channel,
    before or after a stream, in its gaps), airspeed_mps (K,) (NaN likewise; ground speed
    minus the wind where the log has those and no airspeed), one line per thing to know
    (slow streams, absent streams, mixed outputs the log contradicts, an estimated
    airspeed), start_stamp_s the log's start in its own clock [s] (FlightLog.start_stamp_s)
    and setpoints (K, 3) the autopilot's (detection.generators.SETPOINTS: commanded roll,
    pitch [rad], vertical velocity [m/s]; NaN where the log has none)."""

    times_s: np.ndarray
    state: np.ndarray
    controls: np.ndarray
    airspeed_mps: np.ndarray
    warnings: tuple[str, ...]
    start_stamp_s: float = 0.0
    setpoints: np.ndarray | None = None

    @property
    def flight(self) -> DetectorFlight:
        """What self_tuning.run_detector and calibrate take."""
        return DetectorFlight(self.times_s, self.state, self.controls, self.airspeed_mps,
                              self.setpoints)


def _surfaces(log: FlightLog, airframe: Airframe | None) -> tuple[str, TimedSeries]:
    """The surface deflections and the stream they come from: the log's own SURFACES (the
    project's recordings), else its OUTPUTS through the airframe; ValueError without either."""
    if SURFACES in log.streams:
        return SURFACES, log.streams[SURFACES]
    if airframe is None:
        raise ValueError(f"log {log.source}: actuator outputs need an airframe file to "
                         "become surface deflections")
    return OUTPUTS, surface_deflections(log, airframe)


def _fill(target: np.ndarray, channels: tuple[str, ...], columns: tuple[str, ...],
          values: np.ndarray) -> None:
    """target[:, channel] = values[:, column] for each column (named as its channel)."""
    for index, column in enumerate(columns):
        target[:, channels.index(column)] = values[:, index]


def detector_samples(log: FlightLog, airframe: Airframe | None,
                     period_s: float) -> DetectorInputs:
    """The log on the grid of period_s [s] (the calibration's sample_period_s): every
    multiple of it where both the body rates and the surfaces have begun and not yet ended
    (the detector can use no other). Rates, attitude and airspeed interpolated, surfaces held
    (the module's docstring). airframe maps the log's OUTPUTS (None for a log with SURFACES).
    ValueError (one line) without body rates or surfaces, or when they do not overlap."""
    if BODY_RATES not in log.streams:
        raise ValueError(log.missing(BODY_RATES, "the detector needs"))
    rates = log.streams[BODY_RATES]
    surfaces_name, surfaces = _surfaces(log, airframe)
    times_s = np.zeros(0)
    if rates.times_s.size and surfaces.times_s.size:
        times_s = grid_times_s(max(rates.times_s[0], surfaces.times_s[0]),
                               min(rates.times_s[-1], surfaces.times_s[-1]), period_s)
    if times_s.size == 0:
        raise ValueError(f"log {log.source}: its body rates and surfaces share no instant "
                         f"of the {period_s:g} s grid")
    state = np.full((times_s.size, len(STATE_CHANNELS)), np.nan)
    controls = np.full((times_s.size, len(CONTROL_CHANNELS)), np.nan)
    airspeed_mps = np.full(times_s.size, np.nan)
    _fill(state, STATE_CHANNELS, rates.columns, resample(rates, times_s, LINEAR))
    _fill(controls, CONTROL_CHANNELS, surfaces.columns, resample(surfaces, times_s, LINEAR))
    if ATTITUDE in log.streams:
        attitude = log.streams[ATTITUDE]
        _fill(state, STATE_CHANNELS, attitude.columns, resample(attitude, times_s, ANGULAR))
    if GROUND_VELOCITY in log.streams:
        velocity = log.streams[GROUND_VELOCITY]
        _fill(state, STATE_CHANNELS, velocity.columns, resample(velocity, times_s, LINEAR))
    setpoints = np.column_stack([
        resample(log.streams[name], times_s, method)[:, column] if name in log.streams
        else np.full(times_s.size, np.nan) for name, method, column in (
            (ROLL_SETPOINT, ANGULAR, 0), (PITCH_SETPOINT, ANGULAR, 0),
            (VELOCITY_SETPOINT, LINEAR, 2))])  # generators.SETPOINTS order
    warnings = _warnings(log, airframe, surfaces_name, surfaces, period_s)
    if AIRSPEED in log.streams:
        airspeed_mps = resample(log.streams[AIRSPEED], times_s, LINEAR)[:, 0]
    elif has_airspeed_proxy(log):
        airspeed_mps = _air_relative_speed_mps(state, resample(log.streams[WIND], times_s,
                                                               LINEAR))
        warnings.append(f"log {log.source}: airspeed taken as the ground velocity less the "
                        "autopilot's wind estimate (horizontal)")
    return DetectorInputs(times_s, state, controls, airspeed_mps, tuple(warnings),
                          log.start_stamp_s, setpoints)


def has_airspeed_proxy(log: FlightLog) -> bool:
    """Whether the log has what stands in for a missing airspeed: ground velocity and wind."""
    return GROUND_VELOCITY in log.streams and WIND in log.streams


def _air_relative_speed_mps(state: np.ndarray, wind_mps: np.ndarray) -> np.ndarray:
    """|v_ground - v_wind| horizontally [m/s] (K,): an airspeed proxy, from the state's
    ground velocity and the wind (K, 2) north and east."""
    ground = state[:, [STATE_CHANNELS.index("velocity_north"),
                       STATE_CHANNELS.index("velocity_east")]]
    return np.linalg.norm(ground - wind_mps, axis=1)


def _warnings(log: FlightLog, airframe: Airframe | None, surfaces_name: str,
              surfaces: TimedSeries, period_s: float) -> list[str]:
    """detector_samples' lines: the reader's own, streams absent or slower than the grid, an
    airspeed other than the airframe names, mixed outputs the log contradicts."""
    proxy = has_airspeed_proxy(log)
    lines = [*log.warnings, *(f"log {log.source}: no {name} stream (NaN on the grid)"
                              for name in (ATTITUDE, AIRSPEED) if name not in log.streams
                              and not (name == AIRSPEED and proxy))]
    streams = {name: log.streams[name] for name in (BODY_RATES, ATTITUDE, AIRSPEED)
               if name in log.streams}
    for name, series in {**streams, surfaces_name: surfaces}.items():
        line = slow_stream_warning(name, series, period_s)
        if line is not None:
            lines.append(f"log {log.source}: {line}")
    if airframe is None:
        return lines
    wanted = airframe.airspeed_source
    if wanted and log.airspeed_source and wanted != log.airspeed_source:
        lines.append(f"log {log.source}: its airspeed is {log.airspeed_source}, airframe "
                     f"{airframe.path} names {wanted}")
    if surfaces_name == OUTPUTS:
        lines += mixed_output_mismatches(log, airframe)
    return lines
