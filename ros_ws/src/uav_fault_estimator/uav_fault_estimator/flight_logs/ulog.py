"""PX4 ULog files (.ulg) as flight logs, with pyulog.

Topics read (the first instance of each; a topic missing gives no stream):
- vehicle_angular_velocity: xyz [rad/s], FRD -> BODY_RATES;
- vehicle_attitude: q (w, x, y, z), FRD body to NED -> ATTITUDE;
- airspeed_validated: true_airspeed_m_s, else calibrated_airspeed_m_s, else
  indicated_airspeed_m_s (the first with a finite value in the log; FlightLog.airspeed_source
  says which) -> AIRSPEED;
- actuator_outputs: output[0 .. noutputs-1] [PWM us] -> OUTPUTS output_1 .. (unit "pwm_us");
  without it, actuator_servos control[0..7] -> output_1..8 and actuator_motors
  control[0..11] -> output_9.. held at the servos' instants (a motor keeps its last
  command), or else actuator_controls_0 (older PX4: roll, pitch, yaw, throttle, ...)
  control[0..7] -> output_1..8; all normalised (unit "normalised").
Times are the messages' `timestamp` [us since boot] in seconds from the log's start (the
file header's timestamp).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pyulog import ULog
from pyulog.exceptions import ULogException

from uav_fault_estimator.flight_logs.axes import body_rates_frd, euler_from_quaternions
from uav_fault_estimator.flight_logs.streams import (
    AIRSPEED,
    ATTITUDE,
    BODY_RATES,
    OUTPUTS,
    STREAM_COLUMNS,
    FlightLog,
    TimedSeries,
    ordered_series,
)

RATES, ATTITUDE_TOPIC, AIRSPEED_TOPIC = (
    "vehicle_angular_velocity", "vehicle_attitude", "airspeed_validated")
PWM_OUTPUTS, SERVOS, MOTORS, CONTROLS = (
    "actuator_outputs", "actuator_servos", "actuator_motors", "actuator_controls_0")
TOPICS = (RATES, ATTITUDE_TOPIC, AIRSPEED_TOPIC, PWM_OUTPUTS, SERVOS, MOTORS, CONTROLS)
# airspeed_validated's fields in order of preference, with the source they are
AIRSPEED_FIELDS = (("true_airspeed_m_s", "true"), ("calibrated_airspeed_m_s", "calibrated"),
                   ("indicated_airspeed_m_s", "indicated"))
US_PER_S = 1e6
FILE_HEADER_BYTES, MESSAGE_HEADER_BYTES = 16, 3  # ULog: magic, version, timestamp; size, type


def read_ulog(path: Path, axes: str = "FRD") -> FlightLog:
    """The flight in a PX4 ULog file. axes ("FRD", PX4's; "FLU" for a log that differs) is
    the convention of its rates and attitude. ValueError (one line naming the file) when it
    is not a readable ULog."""
    path = Path(path)
    log = open_ulog(path, TOPICS)
    data = topic_data(log)
    start_us = log.start_timestamp
    streams: dict[str, TimedSeries] = {}

    def add(name: str, series: TimedSeries | None) -> None:
        if series is not None:
            streams[name] = series

    if RATES in data:
        rates = body_rates_frd(_array(data[RATES], "xyz", 3), axes)
        add(BODY_RATES, _series(data[RATES], start_us, rates, STREAM_COLUMNS[BODY_RATES]))
    if ATTITUDE_TOPIC in data:
        euler = euler_from_quaternions(_array(data[ATTITUDE_TOPIC], "q", 4), axes)
        add(ATTITUDE, _series(data[ATTITUDE_TOPIC], start_us, euler,
                              STREAM_COLUMNS[ATTITUDE]))
    airspeed_source = ""
    if AIRSPEED_TOPIC in data:
        airspeed, airspeed_source = _airspeed(data[AIRSPEED_TOPIC])
        if airspeed is not None:
            add(AIRSPEED, _series(data[AIRSPEED_TOPIC], start_us, airspeed[:, None],
                                  STREAM_COLUMNS[AIRSPEED]))
    outputs, output_unit = _outputs(data, start_us)
    add(OUTPUTS, outputs)
    damaged = (f"log {path}: damaged ULog (truncated or corrupt data, pyulog): read up to "
               "the damage and past what it could resynchronise on; samples may be missing",)
    return FlightLog(name=path.stem, source=str(path), format="ulog", streams=streams,
                     output_unit=output_unit, airspeed_source=airspeed_source,
                     warnings=damaged if log.file_corruption or _cut_short(path) else (),
                     start_stamp_s=start_us / US_PER_S)


def open_ulog(path: Path, topics: tuple[str, ...]) -> ULog:
    """The ULog file at path with the named topics' data; ValueError (one line naming the
    file) when it is not a readable ULog."""
    try:
        return ULog(str(path), message_name_filter_list=list(topics))
    except (ULogException, OSError, ValueError, IndexError) as error:
        reason = " ".join(str(error).split()) or type(error).__name__
        raise ValueError(f"{path}: not a readable PX4 ULog ({reason})") from None


def topic_data(log: ULog) -> dict[str, dict]:
    """The first instance of each topic in log: its fields by pyulog's names (arrays
    field[0], field[1], ...) as arrays, `timestamp` [us since boot] among them."""
    return {d.name: d.data for d in log.data_list if d.multi_id == 0}


def _cut_short(path: Path) -> bool:
    """Whether the file ends inside a message (a log cut short: pyulog stops there without
    a word). Walks the messages' headers, each a uint16 payload size and a uint8 type."""
    data = path.read_bytes()
    offset = FILE_HEADER_BYTES
    while offset + MESSAGE_HEADER_BYTES <= len(data):
        offset += MESSAGE_HEADER_BYTES + int.from_bytes(data[offset:offset + 2], "little")
    return offset != len(data)


def _array(topic: dict, field: str, size: int) -> np.ndarray:
    """A topic's array field (pyulog names its elements field[0], field[1], ...) as
    (n, size) floats."""
    return np.column_stack([topic[f"{field}[{k}]"] for k in range(size)]).astype(float)


def _times_s(topic: dict, start_us: int) -> np.ndarray:
    """A topic's timestamps [us since boot] in seconds from the log's start."""
    return (topic["timestamp"].astype(np.int64) - np.int64(start_us)) / US_PER_S


def _series(topic: dict, start_us: int, values: np.ndarray,
            columns: tuple[str, ...]) -> TimedSeries | None:
    """A topic's values (n, k) at its timestamps."""
    return ordered_series(_times_s(topic, start_us), values, columns)


def _airspeed(topic: dict) -> tuple[np.ndarray | None, str]:
    """airspeed_validated's preferred airspeed [m/s] (n,) and its source; None, "" when no
    field has a finite value."""
    for field, source in AIRSPEED_FIELDS:
        if field in topic and np.isfinite(topic[field]).any():
            return topic[field].astype(float), source
    return None, ""


def _outputs(data: dict, start_us: int) -> tuple[TimedSeries | None, str]:
    """The OUTPUTS stream and its unit: PWM from actuator_outputs, else normalised."""
    if PWM_OUTPUTS in data:
        topic = data[PWM_OUTPUTS]
        count = int(topic["noutputs"].max()) if "noutputs" in topic else _width(topic, "output")
        return _output_series(topic, start_us, _array(topic, "output", count)), "pwm_us"
    if SERVOS in data:
        servos = data[SERVOS]
        values = _array(servos, "control", _width(servos, "control"))
        if MOTORS in data:
            values = np.hstack([values, _held(data[MOTORS], _times_s(servos, start_us),
                                              start_us)])
        return _output_series(servos, start_us, values), "normalised"
    if CONTROLS in data:
        topic = data[CONTROLS]
        return _output_series(topic, start_us, _array(topic, "control",
                                                      _width(topic, "control"))), "normalised"
    return None, "pwm_us"


def _width(topic: dict, field: str) -> int:
    """How many elements the topic's array field has."""
    return sum(1 for name in topic if name.startswith(f"{field}["))


def _held(motors: dict, times_s: np.ndarray, start_us: int) -> np.ndarray:
    """actuator_motors' controls at times_s [s]: the last at or before each (NaN before the
    first), (n, motors)."""
    motor_times_s = _times_s(motors, start_us)
    order = np.argsort(motor_times_s, kind="stable")
    values = _array(motors, "control", _width(motors, "control"))[order]
    index = np.searchsorted(motor_times_s[order], times_s, side="right") - 1
    held = values[np.clip(index, 0, None)]
    held[index < 0] = np.nan
    return held


def _output_series(topic: dict, start_us: int, values: np.ndarray) -> TimedSeries | None:
    """Output values (n, k) as OUTPUTS output_1 .. output_k at the topic's timestamps."""
    columns = tuple(f"output_{k + 1}" for k in range(values.shape[1]))
    return _series(topic, start_us, values, columns)
