"""A simulated flight as an autopilot would log it: an ArduPilot DataFlash log (.bin) and a
PX4 ULog (.ulg), holding what calibration_logs.py reads (its docstring's table), so that a
calibration from an autopilot's log can be shown and tested without a real aircraft's logs.
No ROS here.

The flight is the simulator's samples (uav_sim.simulation.Sample): each message or topic
once per sample, at the sample's time taken as the autopilot's boot time. What they hold:
the measured state; the surfaces and throttle as the PWM outputs [us] an autopilot drives for
them through the airframe's servo map (uav_aircraft.airframe.outputs_of_controls; an output
it does not drive is 0); the airspeed (none without air data on board); the wind as the
autopilot's estimate, the true wind's north and east (its filtered form is the reader's
work). A log holds no fuel mass, flap, vanes or vertical wind.

DataFlash: written here, field by field in ArduPilot's binary format, since no package on
PyPI writes one (those there, pymavlink's DFReader among them, read or analyse them): an FMT
message per message type (FMT's own first), then the data messages, each the header 0xA3
0x95, its type byte and its fields packed little-endian by its FMT's format characters
(pymavlink's FORMAT_TO_STRUCT: the C type and the factor of each, as AP_Logger/LogStructure.h
defines them). The messages' formats are ArduPilot 4.x's (LogStructure.h, AP_AHRS,
AP_InertialSensor, AP_NavEKF3, AP_RPM); fields the flight does not give are 0. RCOU carries
outputs 1 to 14 (ArduPilot logs the others in RCO2, not written here).

ULog: written here too, following the ULog file format specification (header, flag bits,
format, add-logged-message and data messages), since pyulog 1.3.0's ULog.write_ulog only
writes back a log it has parsed and the other ULog packages on PyPI parse, convert or view
logs: the topics with PX4's field names and types, without padding (which the format
allows), the data messages in time order.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pymavlink.DFReader import FORMAT_TO_STRUCT
from uav_aircraft.airframe import CONTROLS, MAX_OUTPUTS, Airframe, outputs_of_controls
from uav_common.channels import AIRSPEED_INDEX, CONTROL_CHANNELS, state_indices
from uav_sim.simulation import Sample

from uav_fault_estimator.flight_logs.axes import quaternions_from_euler
from uav_fault_estimator.flight_logs.calibration_logs import DATAFLASH_HEADER
from uav_fault_estimator.flight_logs.ulog import US_PER_S


@dataclass(frozen=True)
class LoggedFlight:
    """What the logs hold of a flight, per sample: times_s (K,) [s, the autopilot's boot
    time], states (K, 14) in STATE_CHANNELS order, outputs_us (K, MAX_OUTPUTS) the PWM
    outputs 1.. [us] (0: not driven), airspeed_mps (K,) [m/s] or None without air data,
    wind_ne_mps (K, 2) the wind north, east [m/s]."""

    times_s: np.ndarray
    states: np.ndarray
    outputs_us: np.ndarray
    airspeed_mps: np.ndarray | None
    wind_ne_mps: np.ndarray

    def state(self, *channels: str) -> np.ndarray:
        """The named state channels' columns (K, len(channels))."""
        return self.states[:, state_indices(*channels)]


def logged_flight(samples: Sequence[Sample], airframe: Airframe) -> LoggedFlight:
    """The samples as the logs hold them (the module's docstring); the outputs through the
    airframe's servo map."""
    controls = np.array([sample.controls for sample in samples])
    by_name = controls[:, [CONTROL_CHANNELS.index(name) for name in CONTROLS]]
    outputs_us = np.zeros((len(samples), MAX_OUTPUTS))
    for k, values in enumerate(by_name):
        for output, pwm_us in outputs_of_controls(airframe, dict(zip(CONTROLS, values,
                                                                     strict=True))).items():
            outputs_us[k, output - 1] = pwm_us
    air_data = [sample.air_data for sample in samples]
    return LoggedFlight(
        times_s=np.array([sample.time_s for sample in samples]),
        states=np.array([sample.state for sample in samples]),
        outputs_us=outputs_us,
        airspeed_mps=None if air_data[0] is None
        else np.array([row[AIRSPEED_INDEX] for row in air_data]),
        wind_ne_mps=np.array([sample.wind_ned_mps[:2] for sample in samples]))


# ---- ArduPilot DataFlash -------------------------------------------------------------------

@dataclass(frozen=True)
class DataflashMessage:
    """A DataFlash message type: its name, format characters and column names (ArduPilot's),
    and what of a LoggedFlight its columns hold (by column name, each (K,) in the column's
    unit; every other column 0)."""

    name: str
    format: str
    columns: tuple[str, ...]
    values: Callable[[LoggedFlight], Mapping[str, np.ndarray]]


def _degrees(flight: LoggedFlight, *channels: str) -> np.ndarray:
    """The named state channels [rad] in degrees (K, n)."""
    return np.degrees(flight.state(*channels))


def _attitude_deg(flight: LoggedFlight) -> dict[str, np.ndarray]:
    """Roll, Pitch [deg] and Yaw [deg, 0..360: a uint16 of centidegrees]."""
    roll, pitch, yaw = _degrees(flight, "roll", "pitch", "yaw").T
    return {"Roll": roll, "Pitch": pitch, "Yaw": np.mod(yaw, 360.0)}


def _position(flight: LoggedFlight) -> dict[str, np.ndarray]:
    """POS: Lat, Lng [deg], Alt [m above mean sea level], RelHomeAlt and RelOriginAlt [m]."""
    latitude, longitude = _degrees(flight, "latitude", "longitude").T
    altitude = flight.state("altitude")[:, 0]
    height = altitude - altitude[0]  # above where the log starts: home, and the EKF's origin
    return {"Lat": latitude, "Lng": longitude, "Alt": altitude, "RelHomeAlt": height,
            "RelOriginAlt": height}


def _velocity(flight: LoggedFlight) -> dict[str, np.ndarray]:
    """XKF1: the EKF's attitude as ATT's [deg] and VN, VE, VD [m/s]."""
    velocity = flight.state("velocity_north", "velocity_east", "velocity_down")
    return {**_attitude_deg(flight), **dict(zip(("VN", "VE", "VD"), velocity.T, strict=True))}


# ArduPilot 4.x's formats of the messages calibration_logs reads (module docstring).
DATAFLASH_MESSAGES: tuple[DataflashMessage, ...] = (
    DataflashMessage("ATT", "QccccCCCCB", ("TimeUS", "DesRoll", "Roll", "DesPitch", "Pitch",
                                           "DesYaw", "Yaw", "ErrRP", "ErrYaw", "AEKF"),
                     _attitude_deg),
    DataflashMessage("IMU", "QBffffffIIfBBHH",
                     ("TimeUS", "I", "GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ", "EG",
                      "EA", "T", "GH", "AH", "GHz", "AHz"),
                     lambda flight: dict(zip(("GyrX", "GyrY", "GyrZ"), flight.state(
                         "roll_rate", "pitch_rate", "yaw_rate").T, strict=True))),
    DataflashMessage("POS", "QLLfff",
                     ("TimeUS", "Lat", "Lng", "Alt", "RelHomeAlt", "RelOriginAlt"), _position),
    DataflashMessage("XKF1", "QBccCfffffffccce",
                     ("TimeUS", "C", "Roll", "Pitch", "Yaw", "VN", "VE", "VD", "dPD", "PN",
                      "PE", "PD", "GX", "GY", "GZ", "OH"), _velocity),
    DataflashMessage("XKF2", "QBccccchhhhhhfff",
                     ("TimeUS", "C", "AX", "AY", "AZ", "VWN", "VWE", "MN", "ME", "MD", "MX",
                      "MY", "MZ", "IDX", "IDY", "IS"),
                     lambda flight: {"VWN": flight.wind_ne_mps[:, 0],
                                     "VWE": flight.wind_ne_mps[:, 1]}),
    DataflashMessage("ARSP", "QBffcffBBffB",
                     ("TimeUS", "I", "Airspeed", "DiffPress", "Temp", "RawPress", "Offset", "U",
                      "H", "Hp", "TR", "Pri"),
                     lambda flight: {"Airspeed": flight.airspeed_mps}),
    DataflashMessage("RCOU", "Q" + "H" * 14, ("TimeUS", *(f"C{n}" for n in range(1, 15))),
                     lambda flight: {f"C{n}": flight.outputs_us[:, n - 1]
                                     for n in range(1, 15)}),
    DataflashMessage("RPM", "QBffB", ("TimeUS", "I", "RPM", "Qual", "H"),
                     lambda flight: {"RPM": flight.state("engine_speed")[:, 0]}),
)
DATAFLASH_NAMES = tuple(message.name for message in DATAFLASH_MESSAGES)
FMT_TYPE = 128  # the FMT message's own type (LogStructure.h: LOG_FORMAT_MSG)
FMT = DataflashMessage("FMT", "BBnNZ", ("Type", "Length", "Name", "Format", "Columns"),
                       lambda flight: {})


def write_dataflash(path: Path, samples: Sequence[Sample], airframe: Airframe,
                    messages: Collection[str] = DATAFLASH_NAMES) -> None:
    """The samples (module docstring) as an ArduPilot DataFlash log at path, with the named
    messages (of DATAFLASH_NAMES; ARSP only with air data on board): leave one out for a
    log of an aircraft without that sensor. ValueError for an unknown message name."""
    _check_names(messages, DATAFLASH_NAMES, "DataFlash messages")
    flight = logged_flight(samples, airframe)
    written = [message for message in DATAFLASH_MESSAGES if message.name in messages
               and (message.name != "ARSP" or flight.airspeed_mps is not None)]
    types = {message.name: FMT_TYPE + 1 + k for k, message in enumerate(written)}
    with Path(path).open("wb") as file:
        file.write(_dataflash_format(FMT, FMT_TYPE))
        for message in written:
            file.write(_dataflash_format(message, types[message.name]))
        records = [_dataflash_records(message, types[message.name], flight)
                   for message in written]
        for at_sample in zip(*records, strict=True):
            file.write(b"".join(at_sample))


def _check_names(names: Collection[str], known: Sequence[str], what: str) -> None:
    """ValueError (one line) for a name among names that is not known."""
    unknown = sorted(set(names) - set(known))
    if unknown:
        raise ValueError(f"{what} {unknown}: expected some of {tuple(known)}")


def _struct(message: DataflashMessage) -> struct.Struct:
    """The packing of a message's fields (little-endian, no padding)."""
    return struct.Struct("<" + "".join(FORMAT_TO_STRUCT[c][0] for c in message.format))


def _dataflash_format(message: DataflashMessage, message_type: int) -> bytes:
    """The FMT message that defines a message type: type, length (header included), name,
    format, columns."""
    body = _struct(FMT).pack(message_type, 3 + _struct(message).size, message.name.encode(),
                             message.format.encode(), ",".join(message.columns).encode())
    return DATAFLASH_HEADER + bytes([FMT_TYPE]) + body


def _dataflash_records(message: DataflashMessage, message_type: int,
                       flight: LoggedFlight) -> list[bytes]:
    """The message's data messages, one per sample: each column's value in its format's
    unit (divided by FORMAT_TO_STRUCT's factor where it has one, rounded for an integer
    field), TimeUS the sample's time [us]."""
    given = {"TimeUS": flight.times_s * US_PER_S, **message.values(flight)}
    columns = []
    for column, character in zip(message.columns, message.format, strict=True):
        _, factor, kind = FORMAT_TO_STRUCT[character]
        values = np.asarray(given.get(column, np.zeros(flight.times_s.size)), dtype=float)
        if factor is not None:
            values = values / factor
        integer = kind is not float or factor is not None
        columns.append(np.round(values).astype(np.int64) if integer else values)
    packing = _struct(message)
    header = DATAFLASH_HEADER + bytes([message_type])
    return [header + packing.pack(*row) for row in zip(*(c.tolist() for c in columns),
                                                        strict=True)]


# ---- PX4 ULog ------------------------------------------------------------------------------

ULOG_MAGIC = b"ULog\x01\x12\x35"
ULOG_VERSION = 1
_ULOG_TYPES = {"uint64_t": "<u8", "uint32_t": "<u4", "float": "<f4", "double": "<f8"}
ULOG_OUTPUTS = 16  # actuator_outputs' output[16]


@dataclass(frozen=True)
class UlogTopic:
    """A ULog topic: its name, fields (type, name; an array as "float[4]") in PX4's order
    without padding, and what of a LoggedFlight they hold after the timestamp (each field's
    values, an array's element by element, (K,) each)."""

    name: str
    fields: tuple[tuple[str, str], ...]
    values: Callable[[LoggedFlight], list[np.ndarray]]


def _quaternions(flight: LoggedFlight) -> list[np.ndarray]:
    """q (w, x, y, z): FRD body to NED."""
    return list(quaternions_from_euler(flight.state("roll", "pitch", "yaw"), "FRD").T)


def _actuator_outputs(flight: LoggedFlight) -> list[np.ndarray]:
    """noutputs (the highest output driven) and output[16] [us]."""
    driven = np.flatnonzero(flight.outputs_us.any(axis=0))
    count = int(driven[-1]) + 1 if driven.size else 0
    return [np.full(flight.times_s.size, count), *flight.outputs_us[:, :ULOG_OUTPUTS].T]


_TIMESTAMP = ("uint64_t", "timestamp")
# PX4's topics that calibration_logs reads (module docstring), with the fields written.
ULOG_TOPICS: tuple[UlogTopic, ...] = (
    UlogTopic("vehicle_attitude", (_TIMESTAMP, ("float[4]", "q")), _quaternions),
    UlogTopic("vehicle_angular_velocity",
              (_TIMESTAMP, ("uint64_t", "timestamp_sample"), ("float[3]", "xyz")),
              lambda flight: [np.round(flight.times_s * US_PER_S),
                              *flight.state("roll_rate", "pitch_rate", "yaw_rate").T]),
    UlogTopic("vehicle_global_position",
              (_TIMESTAMP, ("double", "lat"), ("double", "lon"), ("float", "alt")),
              lambda flight: [*np.degrees(flight.state("latitude", "longitude")).T,
                              flight.state("altitude")[:, 0]]),
    UlogTopic("vehicle_local_position",
              (_TIMESTAMP, ("float", "vx"), ("float", "vy"), ("float", "vz")),
              lambda flight: list(flight.state("velocity_north", "velocity_east",
                                               "velocity_down").T)),
    UlogTopic("wind", (_TIMESTAMP, ("float", "windspeed_north"), ("float", "windspeed_east")),
              lambda flight: list(flight.wind_ne_mps.T)),
    UlogTopic("airspeed_validated",
              (_TIMESTAMP, ("float", "indicated_airspeed_m_s"),
               ("float", "calibrated_airspeed_m_s"), ("float", "true_airspeed_m_s")),
              # the true airspeed alone: the simulator's is true, the others are left NaN
              lambda flight: [np.full(flight.times_s.size, math.nan)] * 2
              + [flight.airspeed_mps]),
    UlogTopic("actuator_outputs",
              (_TIMESTAMP, ("uint32_t", "noutputs"), (f"float[{ULOG_OUTPUTS}]", "output")),
              _actuator_outputs),
    UlogTopic("rpm", (_TIMESTAMP, ("float", "rpm_estimate"), ("float", "rpm_raw")),
              lambda flight: [flight.state("engine_speed")[:, 0]] * 2),
)
ULOG_NAMES = tuple(topic.name for topic in ULOG_TOPICS)


def write_ulog(path: Path, samples: Sequence[Sample], airframe: Airframe,
               topics: Collection[str] = ULOG_NAMES) -> None:
    """The samples (module docstring) as a PX4 ULog at path, with the named topics (of
    ULOG_NAMES; airspeed_validated only with air data on board): leave one out for a log of
    an aircraft without that sensor. The log starts at the first sample. ValueError for an
    unknown topic name."""
    _check_names(topics, ULOG_NAMES, "ULog topics")
    flight = logged_flight(samples, airframe)
    written = [topic for topic in ULOG_TOPICS if topic.name in topics
               and (topic.name != "airspeed_validated" or flight.airspeed_mps is not None)]
    timestamps_us = np.round(flight.times_s * US_PER_S).astype(np.uint64)
    data = [[ulog_message(b"D", struct.pack("<H", msg_id) + record)
             for record in ulog_records(topic.fields, [timestamps_us, *topic.values(flight)])]
            for msg_id, topic in enumerate(written)]
    with Path(path).open("wb") as file:
        file.write(ULOG_MAGIC + bytes([ULOG_VERSION]) + struct.pack("<Q", int(timestamps_us[0])))
        file.write(ulog_message(b"B", bytes(40)))  # no flag bits, nothing appended
        for topic in written:
            text = topic.name + ":" + "".join(f"{kind} {name};" for kind, name in topic.fields)
            file.write(ulog_message(b"F", text.encode()))
        for msg_id, topic in enumerate(written):
            file.write(ulog_message(b"A", struct.pack("<BH", 0, msg_id) + topic.name.encode()))
        for at_sample in zip(*data, strict=True):  # in time order
            file.write(b"".join(at_sample))


def ulog_message(kind: bytes, payload: bytes) -> bytes:
    """A ULog message: its payload's size (uint16), its type (a character), the payload."""
    return struct.pack("<H", len(payload)) + kind + payload


def ulog_records(fields: Sequence[tuple[str, str]], values: list[np.ndarray]) -> list[bytes]:
    """A topic's records, one per sample, packed little-endian without padding from its
    fields' (type, name) values (an array's elements one by one, in order)."""
    dtype = []
    for kind, name in fields:
        base, _, size = kind.partition("[")
        count = int(size.rstrip("]")) if size else 1
        dtype += [(f"{name}[{k}]" if size else name, _ULOG_TYPES[base]) for k in range(count)]
    table = np.zeros(values[0].size, dtype=dtype)
    for (name, _), value in zip(dtype, values, strict=True):
        table[name] = value
    return [row.tobytes() for row in table]
