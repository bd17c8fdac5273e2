"""Fault-free flights in an autopilot's own log, as a model calibration reads them: an
ArduPilot DataFlash log (.bin, read with pymavlink's DFReader) or a PX4 ULog (.ulg, pyulog).
No ROS here.

What each column comes from (the first instance of a message or topic: a field I or C of 0,
multi_id 0; the attitude, rates and velocities FRD body axes and NED, as both autopilots log
them):

    column               DataFlash (ArduPilot)            ULog (PX4)
    roll, pitch, yaw     ATT Roll, Pitch, Yaw [deg]       vehicle_attitude q
    p, q, r              IMU GyrX, GyrY, GyrZ [rad/s]     vehicle_angular_velocity xyz
    lat, lon, altitude   POS Lat, Lng [deg], Alt [m]      vehicle_global_position lat, lon
                         (else GPS's)                     [deg], alt [m]
    v north, east, down  XKF1 VN, VE, VD (EKF2: NKF1)     vehicle_local_position vx, vy, vz
    engine speed         RPM RPM (older: rpm1) [rpm]      rpm rpm_estimate (older:
                                                          indicated_frequency_rpm)
    surfaces, throttle   RCOU C1..C14 [PWM us]            actuator_outputs output (ulog.py)
    airspeed             ARSP Airspeed [m/s]              airspeed_validated (ulog.py)
    wind north, east     XKF2 VWN, VWE (EKF2: NKF2)       wind (older: wind_estimate)
                                                          windspeed_north, windspeed_east

ATT's attitude is the AHRS's own (ArduPlane subtracts its pitch trim only from the MAVLink
ATTITUDE it sends, not from the log). ArduPilot's ARSP airspeed is its equivalent airspeed,
taken as it is, as mavlink_node takes VFR_HUD's. An RCOU output of 0 is no output (NaN).

Each stream is resampled onto the multiples of sample_period_s where every needed stream
has begun and not yet ended, by the project's one rule (uav_common.interpolation through
flight_logs.resample: linear, angles the short way round, missing across a stream's gaps).
The surfaces are the PWM outputs through the airframe file's servo map (flight_logs.surfaces,
as the log readers map them); flap 0, mixture and ignition 1 (an autopilot logs none of them:
the engine runs, the flap is retracted), as mavlink_node sends them. The air data is the
airspeed, the angle of attack and sideslip NaN (a small aircraft's log has no vanes; as
mavlink_node publishes them), so a calibration flies these flights on the wind estimate: the
autopilot's (down 0: both estimate the horizontal wind only) through the embedded-estimation
paper's filter (uav_sim.wind.FilteredWind, on the grid: what sim_node publishes as
wind/filtered and mavlink_node's filter of the same time constant gives on its grid). No
autopilot logs the fuel on board: the fuel mass is a constant given (0 for an electric
aircraft, as mavlink_node's fuel_mass_kg).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from pymavlink.DFReader import DFReader_binary
from uav_aircraft.airframe import CONTROLS, Airframe
from uav_common.channels import (
    CONTROL_CHANNELS,
    STATE_CHANNELS,
    UNREPORTED_CONTROLS,
    state_indices,
)
from uav_common.interpolation import ANGULAR, LINEAR
from uav_sim.wind import FilteredWind

from uav_fault_estimator.estimation.model_calibration import SensorFlight
from uav_fault_estimator.flight_logs.replay import air_data_rows
from uav_fault_estimator.flight_logs.resample import grid_times_s, resample
from uav_fault_estimator.flight_logs.streams import (
    AIRSPEED,
    ATTITUDE,
    BODY_RATES,
    GROUND_VELOCITY,
    OUTPUTS,
    STREAM_COLUMNS,
    WIND,
    FlightLog,
    TimedSeries,
    ordered_series,
)
from uav_fault_estimator.flight_logs.surfaces import output_column, surface_deflections
from uav_fault_estimator.flight_logs.ulog import US_PER_S, open_ulog, read_ulog, topic_data

# The streams a calibration needs beyond flight_logs.streams' own, named by their columns.
POSITION = "position"  # latitude, longitude [rad], altitude [m above mean sea level]
ENGINE_SPEED = "engine_speed"  # [rpm]
COLUMNS: Mapping[str, tuple[str, ...]] = {
    **STREAM_COLUMNS, POSITION: ("latitude", "longitude", "altitude"),
    ENGINE_SPEED: ("engine_speed",)}
# What a calibration cannot do without (the air data is optional: NaN without), and how each
# state stream is resampled.
NEEDED = (ATTITUDE, BODY_RATES, POSITION, GROUND_VELOCITY, ENGINE_SPEED, WIND, OUTPUTS)
STATE_METHODS = {ATTITUDE: ANGULAR, BODY_RATES: LINEAR, POSITION: LINEAR,
                 GROUND_VELOCITY: LINEAR, ENGINE_SPEED: LINEAR}
# What the log format's suffix is (a DataFlash log on an SD card is NAME.BIN).
DATAFLASH_SUFFIX, ULOG_SUFFIX = ".bin", ".ulg"
LOG_SUFFIXES = (DATAFLASH_SUFFIX, ULOG_SUFFIX)
DEFAULT_SAMPLE_PERIOD_S = 0.05  # sim_node's 20 Hz and mavlink_node's sample_period_s
# The wind filter's time constant: the shipped scenarios' filter_time_constant_s and
# mavlink_node's wind_filter_tau_s [s].
WIND_FILTER_TAU_S = 10.0
DATAFLASH_HEADER = bytes((0xA3, 0x95))  # every DataFlash message starts so
# A DataFlash message's instance (IMU, GPS, ARSP, RPM) or EKF core: the first is 0
FIRST_INSTANCE_FIELDS = ("I", "C")


class CalibrationLogError(ValueError):
    """A log a calibration cannot read or use; one line naming the file and what is
    missing."""


@dataclass(frozen=True)
class LogSource:
    """Where a stream is in a log: the DataFlash message or ULog topic, its fields in the
    stream's column order, and the factors that turn their units into SI (deg -> rad)."""

    message: str
    fields: tuple[str, ...]
    factors: tuple[float, ...]


_DEG = math.radians(1.0)
_POSITION_FACTORS = (_DEG, _DEG, 1.0)
# Per stream, its sources in order of preference: the first the log has is read.
DATAFLASH_SOURCES: Mapping[str, tuple[LogSource, ...]] = {
    ATTITUDE: (LogSource("ATT", ("Roll", "Pitch", "Yaw"), (_DEG,) * 3),),
    BODY_RATES: (LogSource("IMU", ("GyrX", "GyrY", "GyrZ"), (1.0,) * 3),),
    POSITION: tuple(LogSource(name, ("Lat", "Lng", "Alt"), _POSITION_FACTORS)
                    for name in ("POS", "GPS")),
    GROUND_VELOCITY: tuple(LogSource(name, ("VN", "VE", "VD"), (1.0,) * 3)
                           for name in ("XKF1", "NKF1")),
    WIND: tuple(LogSource(name, ("VWN", "VWE"), (1.0,) * 2) for name in ("XKF2", "NKF2")),
    AIRSPEED: (LogSource("ARSP", ("Airspeed",), (1.0,)),),
    ENGINE_SPEED: tuple(LogSource("RPM", (name,), (1.0,)) for name in ("RPM", "rpm1")),
    OUTPUTS: (LogSource("RCOU", tuple(f"C{n}" for n in range(1, 15)), (1.0,) * 14),),
}
# ULog: the streams read here (read_ulog reads the others) likewise, by topic.
ULOG_SOURCES: Mapping[str, tuple[LogSource, ...]] = {
    POSITION: (LogSource("vehicle_global_position", ("lat", "lon", "alt"), _POSITION_FACTORS),),
    GROUND_VELOCITY: (LogSource("vehicle_local_position", ("vx", "vy", "vz"), (1.0,) * 3),),
    WIND: tuple(LogSource(topic, ("windspeed_north", "windspeed_east"), (1.0,) * 2)
                for topic in ("wind", "wind_estimate")),
    ENGINE_SPEED: tuple(LogSource("rpm", (name,), (1.0,))
                        for name in ("rpm_estimate", "indicated_frequency_rpm")),
}
# The topics read_ulog reads, for the line that says one is missing.
ULOG_READ_TOPICS = {ATTITUDE: ("vehicle_attitude",), BODY_RATES: ("vehicle_angular_velocity",),
                    OUTPUTS: ("actuator_outputs",), AIRSPEED: ("airspeed_validated",)}


def sensor_flight_from_log(path: Path, airframe: Airframe,
                           sample_period_s: float = DEFAULT_SAMPLE_PERIOD_S,
                           fuel_mass_kg: float = 0.0,
                           wind_filter_tau_s: float = WIND_FILTER_TAU_S) -> SensorFlight:
    """The fault-free flight in the DataFlash (.bin) or ULog (.ulg) log at path as a model
    calibration reads it (the module's docstring): on the grid of sample_period_s [s] (times
    in the log's clock: a DataFlash log's boot time, a ULog's time from its start), the
    surfaces through airframe's servo map, the fuel mass fuel_mass_kg [kg], the wind filtered
    with wind_filter_tau_s [s]. CalibrationLogError (one line naming the file) for a file
    that is not such a log or lacks a stream the calibration needs; ValueError (one line) for
    outputs the airframe does not fit."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in LOG_SUFFIXES:
        raise CalibrationLogError(f"{path}: not an autopilot's log (expected an ArduPilot "
                                  f"DataFlash {DATAFLASH_SUFFIX} or a PX4 {ULOG_SUFFIX})")
    if not path.is_file():
        raise CalibrationLogError(f"{path}: no such file")
    log = read_dataflash(path) if suffix == DATAFLASH_SUFFIX else _read_calibration_ulog(path)
    return _on_grid(log, airframe, sample_period_s, fuel_mass_kg, wind_filter_tau_s)


def _on_grid(log: FlightLog, airframe: Airframe, sample_period_s: float, fuel_mass_kg: float,
             wind_filter_tau_s: float) -> SensorFlight:
    """A log's streams (NEEDED, and AIRSPEED where it has one) as a SensorFlight on the grid
    of sample_period_s [s] (sensor_flight_from_log's arguments)."""
    for name in NEEDED:
        if name not in log.streams:
            raise CalibrationLogError(log.missing(name, "a model calibration needs"))
    unmapped = [name for name in CONTROLS if name not in airframe.controls]
    if unmapped:
        raise CalibrationLogError(f"airframe {airframe.path} maps no {', '.join(unmapped)}, "
                                  f"which a model calibration needs (log {log.source})")
    surfaces = surface_deflections(log, airframe)
    used = [surfaces, *(log.streams[name] for name in NEEDED if name != OUTPUTS)]
    times_s = grid_times_s(max(s.times_s[0] for s in used), min(s.times_s[-1] for s in used),
                           sample_period_s)
    if times_s.size == 0:
        raise CalibrationLogError(f"log {log.source}: its streams share no instant of the "
                                  f"{sample_period_s:g} s grid")
    states = np.full((times_s.size, len(STATE_CHANNELS)), np.nan)
    for name, method in STATE_METHODS.items():
        series = log.streams[name]
        states[:, state_indices(*series.columns)] = resample(series, times_s, method)
    states[:, state_indices("fuel_mass")] = fuel_mass_kg
    controls = np.full((times_s.size, len(CONTROL_CHANNELS)), np.nan)
    controls[:, [CONTROL_CHANNELS.index(name) for name in CONTROLS]] = resample(
        surfaces, times_s, LINEAR)
    for index, value in UNREPORTED_CONTROLS.items():
        controls[:, index] = value
    airspeed_mps = (resample(log.streams[AIRSPEED], times_s, LINEAR)[:, 0]
                    if AIRSPEED in log.streams else np.full(times_s.size, np.nan))
    wind_ne_mps = resample(log.streams[WIND], times_s, LINEAR)
    return SensorFlight(log.source, times_s, states, controls,
                        _filtered_wind(wind_ne_mps, sample_period_s, wind_filter_tau_s),
                        air_data_rows(airspeed_mps))


def _filtered_wind(wind_ne_mps: np.ndarray, period_s: float, tau_s: float) -> np.ndarray:
    """The horizontal wind estimate (K, 2) north, east [m/s] on a grid of period_s [s] as
    the filtered wind (K, 3) NED [m/s] (down 0): the paper's filter of time constant tau_s
    [s]. A missing row (NaN) is missing in the output too and the filter holds over it, as
    mavlink_node's does."""
    wind_filter = FilteredWind(tau_s, period_s)
    filtered = np.full((wind_ne_mps.shape[0], 3), np.nan)
    for k, (north_mps, east_mps) in enumerate(wind_ne_mps):
        if math.isfinite(north_mps) and math.isfinite(east_mps):
            filtered[k] = wind_filter.update(np.array([north_mps, east_mps, 0.0]))
    return filtered


# ---- ArduPilot DataFlash ---------------------------------------------------------------------

def read_dataflash(path: Path) -> FlightLog:
    """The streams of DATAFLASH_SOURCES in the DataFlash log at path, each from its first
    source the log has, times TimeUS [s since boot]. CalibrationLogError (one line naming
    the file) when it is not a DataFlash log."""
    with path.open("rb") as file:
        if file.read(len(DATAFLASH_HEADER)) != DATAFLASH_HEADER:
            raise CalibrationLogError(f"{path}: not an ArduPilot DataFlash log (no message "
                                      "header 0xA3 0x95 at its start)")
    rows = _dataflash_rows(path)
    streams = {}
    for name, sources in DATAFLASH_SOURCES.items():
        found = next((rows[source] for source in sources if rows[source][0]), None)
        series = None if found is None else ordered_series(
            *found, _columns(name, len(sources[0].fields)))
        if series is not None:
            streams[name] = series
    if OUTPUTS in streams:  # an output of 0 is ArduPilot's "none"
        outputs = streams[OUTPUTS]
        streams[OUTPUTS] = replace(outputs, values=np.where(outputs.values == 0, np.nan,
                                                            outputs.values))
    return FlightLog(name=path.stem, source=str(path), format="dataflash", streams=streams,
                     sought=_sought(DATAFLASH_SOURCES))


def _dataflash_rows(path: Path) -> dict[LogSource, tuple[list[float], list[list[float]]]]:
    """Per source of DATAFLASH_SOURCES, the times [s since boot] and values (SI) of its
    message's first instance (FIRST_INSTANCE_FIELDS 0) where it has the source's fields."""
    sources = [source for group in DATAFLASH_SOURCES.values() for source in group]
    rows: dict[LogSource, tuple[list[float], list[list[float]]]] = {
        source: ([], []) for source in sources}
    by_message: dict[str, list[LogSource]] = {}
    for source in sources:
        by_message.setdefault(source.message, []).append(source)
    names = list(by_message)
    reader = DFReader_binary(str(path), zero_time_base=True)
    try:
        while (message := reader.recv_match(type=names, strict=True)) is not None:
            fields = set(message.get_fieldnames())
            if any(field in fields and getattr(message, field) != 0
                   for field in FIRST_INSTANCE_FIELDS):
                continue
            for source in by_message[message.get_type()]:
                if fields.issuperset(source.fields):
                    times, values = rows[source]
                    times.append(message.TimeUS / US_PER_S)
                    values.append([getattr(message, field) * factor for field, factor
                                   in zip(source.fields, source.factors, strict=True)])
    finally:
        reader.close()
    return rows


def _sought(sources: Mapping[str, tuple[LogSource, ...]]) -> dict[str, tuple[str, ...]]:
    """Per stream, the messages or topics looked for (FlightLog.sought), each once."""
    return {name: tuple(dict.fromkeys(source.message for source in group))
            for name, group in sources.items()}


def _columns(stream: str, count: int) -> tuple[str, ...]:
    """A stream's columns: COLUMNS', or the OUTPUTS stream's output_1 .. output_count."""
    return tuple(output_column(n) for n in range(1, count + 1)) if stream == OUTPUTS \
        else COLUMNS[stream]


# ---- PX4 ULog ------------------------------------------------------------------------------

def _read_calibration_ulog(path: Path) -> FlightLog:
    """read_ulog's streams (ulog.py) and ULOG_SOURCES' of the ULog at path; CalibrationLogError
    (one line naming the file) when it is not a readable ULog."""
    sought = _sought(ULOG_SOURCES)
    try:
        log = read_ulog(path)
        ulog = open_ulog(path, tuple(topic for topics in sought.values() for topic in topics))
    except ValueError as error:
        raise CalibrationLogError(str(error)) from None
    data = topic_data(ulog)
    streams = dict(log.streams)
    for name, sources in ULOG_SOURCES.items():
        found = (_topic_series(data[source.message], ulog.start_timestamp, source, name)
                 for source in sources if source.message in data
                 and all(field in data[source.message] for field in source.fields))
        series = next((series for series in found if series is not None), None)
        if series is not None:
            streams[name] = series
    return replace(log, streams=streams, sought={**ULOG_READ_TOPICS, **sought})


def _topic_series(topic: dict, start_us: int, source: LogSource,
                  stream: str) -> TimedSeries | None:
    """The stream from a topic (pyulog's fields by name): the source's fields times their
    factors at the topic's timestamps [us since boot], in seconds from the log's start
    (start_us [us]) as ulog.py times its streams; None without a sample."""
    times_s = (topic["timestamp"].astype(np.int64) - np.int64(start_us)) / US_PER_S
    values = np.column_stack([topic[field] * factor for field, factor
                              in zip(source.fields, source.factors, strict=True)])
    return ordered_series(times_s, values, COLUMNS[stream])
