"""What every flight-log reader yields: streams of samples at their own instants, in SI
units and FRD body axes, before any resampling. One home for the stream names and their
columns, shared by the readers, the airframe mapping and the resampling."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np
from uav_aircraft.airframe import CONTROLS

# Stream name -> its columns. The values are SI and in FRD body axes / NED Euler angles
# whatever the log's own convention (the readers convert); `outputs` is the exception: the
# raw actuator outputs, one column per output channel, as the log has them (PWM [us] or
# normalised [-1, 1], FlightLog.output_unit), for the airframe file to map to surfaces.
BODY_RATES = "body_rates"  # roll_rate, pitch_rate, yaw_rate [rad/s], FRD
ATTITUDE = "attitude"  # roll, pitch, yaw [rad], FRD body from NED
AIRSPEED = "airspeed"  # airspeed [m/s]
OUTPUTS = "outputs"  # output_1 ... output_n, raw
# The surfaces already as deflections (the project's own recordings, /controls): aileron,
# elevator, rudder [rad, ControlInputs.msg's signs], throttle [0, 1]; no airframe file needed.
SURFACES = "surfaces"
GROUND_VELOCITY = "ground_velocity"  # velocity_north, velocity_east, velocity_down [m/s]
WIND = "wind"  # wind_north, wind_east [m/s]: the autopilot's estimate, towards which it blows
# The autopilot's commanded attitude (its attitude controller's setpoints) [rad], NED, and
# ground velocity [m/s], NED
ROLL_SETPOINT, PITCH_SETPOINT = "roll_setpoint", "pitch_setpoint"
VELOCITY_SETPOINT = "velocity_setpoint"
STREAM_COLUMNS: Mapping[str, tuple[str, ...]] = {
    BODY_RATES: ("roll_rate", "pitch_rate", "yaw_rate"),
    ATTITUDE: ("roll", "pitch", "yaw"),
    AIRSPEED: ("airspeed",),
    SURFACES: CONTROLS,
    GROUND_VELOCITY: ("velocity_north", "velocity_east", "velocity_down"),
    WIND: ("wind_north", "wind_east"),
    ROLL_SETPOINT: ("roll_setpoint",),
    PITCH_SETPOINT: ("pitch_setpoint",),
    VELOCITY_SETPOINT: ("velocity_north_setpoint", "velocity_east_setpoint",
                        "velocity_down_setpoint"),
}


@dataclass(frozen=True)
class TimedSeries:
    """One stream: times_s (n,) strictly increasing [s, from the log's start]; values (n, k);
    columns (k,) the name of each column."""

    times_s: np.ndarray
    values: np.ndarray
    columns: tuple[str, ...]

    def __post_init__(self) -> None:
        if self.values.ndim != 2 or self.values.shape != (self.times_s.size,
                                                          len(self.columns)):
            raise ValueError(f"a stream of {self.times_s.size} times and columns "
                             f"{self.columns} cannot hold values of shape {self.values.shape}")
        if self.times_s.size > 1 and not np.all(np.diff(self.times_s) > 0):
            raise ValueError("a stream's times must increase strictly")

    @property
    def median_period_s(self) -> float:
        """The median time between samples [s] (inf for fewer than two)."""
        return float(np.median(np.diff(self.times_s))) if self.times_s.size > 1 else np.inf


@dataclass(frozen=True)
class FlightLog:
    """A flight as a reader found it: name (the file's stem), source (the path read), format
    ("ulog", "ros1_bag", "ros2_bag", "csv"), streams by name (STREAM_COLUMNS, OUTPUTS: those
    the log has), output_unit (uav_aircraft.airframe.OUTPUT_UNITS) of the OUTPUTS stream,
    airspeed_source (AIRSPEED_SOURCES there: which airspeed the AIRSPEED stream holds, ""
    when the log has none),
    warnings: what the reader noticed and the user should know (each line names the log;
    a damaged ULog read up to its damage), start_stamp_s: the instant its times count from,
    in the log's own clock [s] (UNIX time for ROS logs, time since boot for ULogs), sought:
    per stream name, what the reader looked for to find it (files, topics), for the line
    that says a needed stream is missing."""

    name: str
    source: str
    format: str
    streams: Mapping[str, TimedSeries]
    output_unit: str = "pwm_us"
    airspeed_source: str = ""
    warnings: tuple[str, ...] = ()
    start_stamp_s: float = 0.0
    sought: Mapping[str, tuple[str, ...]] = field(default_factory=dict)

    def missing(self, stream: str, needed_for: str) -> str:
        """The line for a stream this log lacks and needed_for needs."""
        looked = self.sought.get(stream, ())
        return (f"log {self.source}: no {stream.replace('_', ' ')}, which {needed_for}"
                + (f" (looked for {', '.join(looked)})" if looked else ""))


def ordered_series(times_s: np.ndarray, values: np.ndarray,
                   columns: tuple[str, ...]) -> TimedSeries | None:
    """A stream from a log's samples as they come: times_s (n,) [s], values (n, k). Real logs
    repeat stamps and deliver late messages: the samples are put in time order and of
    samples with the same time the first in the log is kept; samples without a finite time
    are dropped. None when no sample is left."""
    times_s = np.asarray(times_s, dtype=float)
    values = np.asarray(values, dtype=float).reshape(times_s.size, len(columns))
    finite = np.isfinite(times_s)
    times_s, values = times_s[finite], values[finite]
    if times_s.size == 0:
        return None
    order = np.argsort(times_s, kind="stable")
    times_s, values = times_s[order], values[order]
    first = np.concatenate(([True], np.diff(times_s) > 0))
    return TimedSeries(times_s[first], values[first], tuple(columns))


def without_dead_airspeed(log: FlightLog) -> FlightLog:
    """The log without its airspeed stream when that is 0 in every sample (a sensor not
    fitted or not read: ALFA's flights from 2018-09-11 on), said in its warnings; else the
    log itself."""
    series = log.streams.get(AIRSPEED)
    if series is None or np.any(series.values != 0.0):
        return log
    streams = {name: s for name, s in log.streams.items() if name != AIRSPEED}
    return replace(log, streams=streams, airspeed_source="", warnings=(
        *log.warnings, f"log {log.source}: its airspeed is 0 throughout: read as no airspeed"))
