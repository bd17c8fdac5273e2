"""What the topics of a ROS log mean: MAVROS's message types and the project's own, as
streams (streams.py). One home for the field meanings, shared by the bag reader (bags.py)
and the reader of per-topic CSV exports (csv_logs.py): both hand over a topic's fields as
arrays by dotted path relative to the message ("angular_velocity.x"; an array field such as
RCOut's "channels" as (n, k)) and its message times.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
from rosbags.typesys import get_types_from_msg
from rosbags.typesys.store import Typestore
from uav_common.channels import (
    AIR_DATA_FIELDS,
    CONTROL_CHANNELS,
    CONTROL_UNITS,
    STATE_CHANNELS,
    STATE_UNITS,
    field_name,
)

from uav_fault_estimator.flight_logs.axes import (
    body_rates_frd,
    euler_frd,
    euler_from_quaternions,
    world_vectors_ned,
)
from uav_fault_estimator.flight_logs.streams import (
    AIRSPEED,
    ATTITUDE,
    BODY_RATES,
    GROUND_VELOCITY,
    OUTPUTS,
    PITCH_SETPOINT,
    ROLL_SETPOINT,
    STREAM_COLUMNS,
    SURFACES,
    VELOCITY_SETPOINT,
    WIND,
    TimedSeries,
    ordered_series,
)

# MAVROS's own message types are not in rosbags' type stores. Their definitions, as
# mavros_msgs/msg/RCOut.msg and VFR_HUD.msg have them in the mavros repository (ROS 1 and
# ROS 2 alike; comments dropped).
MAVROS_DEFINITIONS: Mapping[str, str] = {
    "mavros_msgs/msg/RCOut": "std_msgs/Header header\nuint16[] channels\n",
    "mavros_msgs/msg/VFR_HUD": (
        "std_msgs/Header header\n"
        "float32 airspeed\n"  # m/s; MAVLink: calibrated or indicated for a fixed wing
        "float32 groundspeed\n"
        "int16 heading\n"
        "float32 throttle\n"
        "float32 altitude\n"
        "float32 climb\n"
    ),
}

Fields = Mapping[str, np.ndarray]
Streams = dict[str, TimedSeries]


@dataclass(frozen=True)
class TopicMeaning:
    """How one message type becomes streams: its type, the fields it reads (dotted paths;
    arrays named bare), which of them are arrays, the axes of its rates and attitude
    ("FRD" or "FLU", axes.py), the airspeed it holds (uav_aircraft.airframe.AIRSPEED_SOURCES,
    "" none), streams(times_s, fields, axes) -> the streams by name, and the names of the streams it
    can give."""

    message_type: str
    fields: tuple[str, ...]
    array_fields: tuple[str, ...]
    axes: str
    airspeed_source: str
    streams: Callable[[np.ndarray, Fields, str], Streams]
    gives: tuple[str, ...]


def _columns(fields: Fields, names: tuple[str, ...]) -> np.ndarray:
    """The named fields side by side (n, len(names)) as floats."""
    return np.column_stack([np.asarray(fields[name], dtype=float) for name in names])


def _streams(times_s: np.ndarray, **values: np.ndarray) -> Streams:
    """The streams by name (STREAM_COLUMNS) of values at times_s; an empty or all-NaN stream
    left out (MAVROS's imu/data_raw has no orientation: an all-zero quaternion)."""
    streams = {}
    for name, value in values.items():
        series = ordered_series(times_s, value, STREAM_COLUMNS[name])
        if series is not None and not np.isnan(series.values).all():
            streams[name] = series
    return streams


def _imu(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
    """sensor_msgs/Imu: angular_velocity [rad/s] and orientation (body to world)."""
    rates = _columns(fields, tuple(f"angular_velocity.{axis}" for axis in "xyz"))
    quaternions = _columns(fields, tuple(f"orientation.{axis}" for axis in "wxyz"))
    return _streams(times_s, **{BODY_RATES: body_rates_frd(rates, axes),
                                ATTITUDE: euler_from_quaternions(quaternions, axes)})


def _rc_out(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
    """mavros_msgs/RCOut: channels [PWM us], one output column each."""
    channels = np.asarray(fields["channels"], dtype=float)
    columns = tuple(f"output_{k + 1}" for k in range(channels.shape[1]))
    series = ordered_series(times_s, channels, columns)
    return {OUTPUTS: series} if series is not None else {}


def _vfr_hud(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
    """mavros_msgs/VFR_HUD: airspeed [m/s]."""
    return _streams(times_s, **{AIRSPEED: _columns(fields, ("airspeed",))})


_LINEAR = tuple(f"twist.linear.{axis}" for axis in "xyz")


def _ground_velocity(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
    """geometry_msgs/TwistStamped of MAVROS's local_position/velocity: the ground velocity
    [m/s] in the log's world frame."""
    return _streams(times_s, **{GROUND_VELOCITY: world_vectors_ned(_columns(fields, _LINEAR),
                                                                   axes)})


def _wind(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
    """geometry_msgs/TwistStamped of MAVROS's wind_estimation: the wind [m/s] (the velocity
    of the air over the ground) in the log's world frame; its horizontal part."""
    return _streams(times_s, **{WIND: world_vectors_ned(_columns(fields, _LINEAR),
                                                        axes)[:, :2]})


def _euler(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
    """geometry_msgs/Vector3 of roll, pitch, yaw [rad] (x, y, z) of the log's body axes from
    its world frame (ALFA's /mavctrl/rpy, FLU from ENU)."""
    euler = _columns(fields, ("x", "y", "z"))
    return _streams(times_s, **{ATTITUDE: euler_frd(euler, axes)})


def _setpoint(stream: str) -> Callable[[np.ndarray, Fields, str], Streams]:
    """The streams of a commanded/measured pair in degrees (ALFA's /mavros/nav_info/roll and
    /pitch: PX4's own NED angles, whatever the log's axes): the commanded angle [rad]."""
    def streams(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
        return _streams(times_s, **{stream: np.radians(_columns(fields, ("commanded",)))})
    return streams


_VELOCITY_COMMAND_FIELDS = ("des_x", "des_y", "des_z")


def _velocity_setpoint(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
    """ALFA's /mavros/nav_info/velocity (des_x/y/z commanded, meas_x/y/z measured; PX4's own
    NED whatever the log's axes: meas_x/y/z match local_position's north, east, down): the
    commanded ground velocity [m/s]."""
    return _streams(times_s, **{VELOCITY_SETPOINT: _columns(fields, _VELOCITY_COMMAND_FIELDS)})


STATE_FIELDS = dict(zip(STATE_CHANNELS, map(field_name, STATE_CHANNELS, STATE_UNITS),
                        strict=True))
CONTROL_FIELDS = dict(zip(CONTROL_CHANNELS, map(field_name, CONTROL_CHANNELS, CONTROL_UNITS),
                          strict=True))
_RATES = ("roll_rate", "pitch_rate", "yaw_rate")
_EULER = ("roll", "pitch", "yaw")


def _state(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
    """uav_fault_msgs/AircraftState: body rates [rad/s] and Euler angles [rad]."""
    rates = _columns(fields, tuple(STATE_FIELDS[name] for name in _RATES))
    euler = _columns(fields, tuple(STATE_FIELDS[name] for name in _EULER))
    return _streams(times_s, **{BODY_RATES: body_rates_frd(rates, axes),
                                ATTITUDE: euler_frd(euler, axes)})


def _controls(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
    """uav_fault_msgs/ControlInputs: deflections [rad] and throttle [0, 1]."""
    names = tuple(CONTROL_FIELDS[name] for name in STREAM_COLUMNS[SURFACES])
    return _streams(times_s, **{SURFACES: _columns(fields, names)})


def _air_data(times_s: np.ndarray, fields: Fields, axes: str) -> Streams:
    """uav_fault_msgs/AirData: true airspeed [m/s]."""
    return _streams(times_s, **{AIRSPEED: _columns(fields, AIR_DATA_FIELDS[:1])})


IMU, RC_OUT, VFR_HUD = "imu", "rc_out", "vfr_hud"
VELOCITY, WIND_ESTIMATE, EULER = "velocity", "wind_estimate", "euler"
ROLL_COMMAND, PITCH_COMMAND = "roll_command", "pitch_command"
VELOCITY_COMMAND = "velocity_command"
STATE, CONTROLS, AIR_DATA = "state", "controls", "air_data"
_COMMAND_FIELDS = ("commanded", "measured")
MEANINGS: Mapping[str, TopicMeaning] = {
    IMU: TopicMeaning("sensor_msgs/msg/Imu",
                      tuple(f"{vector}.{axis}" for vector in ("angular_velocity", "orientation")
                            for axis in ("xyz" if vector == "angular_velocity" else "wxyz")),
                      (), "FLU", "", _imu, (BODY_RATES, ATTITUDE)),
    RC_OUT: TopicMeaning("mavros_msgs/msg/RCOut", ("channels",), ("channels",), "FLU", "",
                         _rc_out, (OUTPUTS,)),
    VFR_HUD: TopicMeaning("mavros_msgs/msg/VFR_HUD", ("airspeed",), (), "FLU", "indicated",
                          _vfr_hud, (AIRSPEED,)),
    VELOCITY: TopicMeaning("geometry_msgs/msg/TwistStamped", _LINEAR, (), "FLU", "",
                           _ground_velocity, (GROUND_VELOCITY,)),
    WIND_ESTIMATE: TopicMeaning("geometry_msgs/msg/TwistStamped", _LINEAR, (), "FLU", "",
                                _wind, (WIND,)),
    EULER: TopicMeaning("geometry_msgs/msg/Vector3", ("x", "y", "z"), (), "FLU", "", _euler,
                        (ATTITUDE,)),
    # ALFA's nav_info messages (header, commanded, measured; not a MAVROS type)
    ROLL_COMMAND: TopicMeaning("mavros_msgs/msg/NavInfo", _COMMAND_FIELDS, (), "FRD", "",
                               _setpoint(ROLL_SETPOINT), (ROLL_SETPOINT,)),
    PITCH_COMMAND: TopicMeaning("mavros_msgs/msg/NavInfo", _COMMAND_FIELDS, (), "FRD", "",
                                _setpoint(PITCH_SETPOINT), (PITCH_SETPOINT,)),
    VELOCITY_COMMAND: TopicMeaning("mavros_msgs/msg/NavInfoVelocity", _VELOCITY_COMMAND_FIELDS,
                                   (), "FRD", "", _velocity_setpoint, (VELOCITY_SETPOINT,)),
    STATE: TopicMeaning("uav_fault_msgs/msg/AircraftState",
                        tuple(STATE_FIELDS[name] for name in _RATES + _EULER), (), "FRD", "",
                        _state, (BODY_RATES, ATTITUDE)),
    CONTROLS: TopicMeaning("uav_fault_msgs/msg/ControlInputs",
                           tuple(CONTROL_FIELDS[name] for name in STREAM_COLUMNS[SURFACES]),
                           (), "FRD", "", _controls, (SURFACES,)),
    AIR_DATA: TopicMeaning("uav_fault_msgs/msg/AirData", AIR_DATA_FIELDS[:1], (), "FRD", "true",
                           _air_data, (AIRSPEED,)),
}
# Topic name -> meaning, by default: MAVROS's (with the topics ALFA's flights add) and the
# project's own recordings' (sim_node's). Where two topics give one stream (imu/data and
# imu/data_raw both give body rates), the faster is kept (LogStreams.add).
MAVROS_TOPICS: Mapping[str, str] = {
    "/mavros/imu/data": IMU, "/mavros/imu/data_raw": IMU, "/mavros/rc/out": RC_OUT,
    "/mavros/vfr_hud": VFR_HUD, "/mavros/local_position/velocity": VELOCITY,
    "/mavros/wind_estimation": WIND_ESTIMATE, "/mavctrl/rpy": EULER,
    "/mavros/nav_info/roll": ROLL_COMMAND, "/mavros/nav_info/pitch": PITCH_COMMAND,
    "/mavros/nav_info/velocity": VELOCITY_COMMAND}
PROJECT_TOPICS: Mapping[str, str] = {"/state": STATE, "/controls": CONTROLS, "/air_data": AIR_DATA}
DEFAULT_TOPICS: Mapping[str, str] = {**MAVROS_TOPICS, **PROJECT_TOPICS}


def checked_topics(topics: Mapping[str, str] | None) -> Mapping[str, str]:
    """The topics to read (topic name -> MEANINGS key), DEFAULT_TOPICS for None; ValueError
    for an unknown meaning."""
    topics = DEFAULT_TOPICS if topics is None else topics
    for topic, meaning in topics.items():
        if meaning not in MEANINGS:
            raise ValueError(f"topic {topic}: unknown meaning {meaning!r} (expected one of "
                             f"{', '.join(MEANINGS)})")
    return topics


def register_mavros_types(typestore: Typestore) -> Typestore:
    """The type store with MAVROS_DEFINITIONS registered (those it lacks); returned."""
    for name, definition in MAVROS_DEFINITIONS.items():
        if name not in typestore.fielddefs:
            typestore.register(get_types_from_msg(definition, name))
    return typestore


def padded_rows(arrays: list) -> np.ndarray:
    """Arrays of possibly different lengths (an array field's values, message by message) as
    rows (n, longest), NaN-padded."""
    width = max((len(array) for array in arrays), default=0)
    rows = np.full((len(arrays), width), np.nan)
    for row, array in zip(rows, arrays, strict=True):
        row[:len(array)] = array
    return rows


def message_times_ns(stamps_ns: np.ndarray, log_times_ns: np.ndarray) -> np.ndarray:
    """Each message's time [ns]: its header stamp [ns], or where it has none (0: a message
    without a header, or one never stamped) the time it was logged [ns]."""
    return np.where(stamps_ns > 0, stamps_ns, log_times_ns)


def message_times_s(stamps_ns: np.ndarray, log_times_ns: np.ndarray,
                    start_ns: int) -> np.ndarray:
    """Each message's time (message_times_ns) [s from start_ns]."""
    return (message_times_ns(stamps_ns, log_times_ns) - start_ns) * 1e-9


def sought_topics(topics: Mapping[str, str],
                  spelled: Callable[[str], str] = str) -> dict[str, tuple[str, ...]]:
    """Per stream name, the topics (as spelled(topic): a file name, say) that could give it."""
    sought: dict[str, tuple[str, ...]] = {}
    for topic, meaning in topics.items():
        for stream in MEANINGS[meaning].gives:
            sought[stream] = (*sought.get(stream, ()), spelled(topic))
    return sought


@dataclass
class LogStreams:
    """The streams a log's topics gave, merged: by name, the topic each came from, the
    airspeed's source, and a line for each stream two topics gave."""

    streams: dict[str, TimedSeries] = field(default_factory=dict)
    origins: dict[str, str] = field(default_factory=dict)
    airspeed_source: str = ""
    notes: list[str] = field(default_factory=list)

    def add(self, topic: str, meaning: TopicMeaning, streams: Streams) -> None:
        """The streams of one topic of that meaning. A stream another topic gave already is
        kept from the faster of the two (the shorter median period), and said in notes."""
        for name, series in streams.items():
            if name in self.streams:
                kept, dropped = ((topic, series), (self.origins[name], self.streams[name]))
                if series.median_period_s >= self.streams[name].median_period_s:
                    kept, dropped = dropped, kept
                self.notes.append(f"{name} from {kept[0]} ({_rate_hz(kept[1]):.1f} Hz), "
                                  f"not {dropped[0]} ({_rate_hz(dropped[1]):.1f} Hz)")
                if kept[0] != topic:
                    continue
            self.streams[name] = series
            self.origins[name] = topic
            if name == AIRSPEED:
                self.airspeed_source = meaning.airspeed_source


def _rate_hz(series: TimedSeries) -> float:
    return 1.0 / series.median_period_s
