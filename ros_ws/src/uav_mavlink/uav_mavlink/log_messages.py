"""A flight log as the MAVLink messages its autopilot sent, in time order, each with the
autopilot's boot time it went out at: what log_streamer plays to a link. No ROS here.

The logs are read with the project's flight-log readers (uav_fault_estimator.flight_logs)
and each message is packed as autopilot_emulator packs it (units: docs/onboard.md).

ALFA's flight folders (ArduPlane logged through MAVROS, one CSV file a topic): each topic
was made by MAVROS from one message, so each row becomes that message again (MAVROS's ENU
world and FLU body axes back to NED and FRD):

- /mavros/imu/data -> ATTITUDE (orientation and angular velocity);
- /mavros/imu/data_raw -> RAW_IMU (angular velocity and linear acceleration, which MAVROS
  scaled from ArduPilot's whole mrad/s and mG: the round trip is exact);
- /mavros/rc/out -> SERVO_OUTPUT_RAW (channels0..7 as outputs 1..8);
- /mavros/vfr_hud -> VFR_HUD (throttle 0..1 back to %);
- /mavros/local_position/velocity -> LOCAL_POSITION_NED (the velocity; the position is not
  in the folder: NaN);
- /mavros/wind_estimation -> WIND (ArduPilot's: where the wind comes from, its speed);
- /mavros/nav_info/roll and /pitch -> NAV_CONTROLLER_OUTPUT (the commanded angles, each roll
  row with the pitch row nearest it in time);
- /mavros/nav_info/velocity -> POSITION_TARGET_GLOBAL_INT (the commanded velocity, NED);
- a HEARTBEAT (ArduPlane, AUTO) every second.
The onboard computer's own topics (/mavctrl/rpy, the failure status) were never MAVLink
messages and are not sent.

PX4 ULogs (the topics flight_logs.ulog reads, and two more): vehicle_attitude with the latest
vehicle_angular_velocity -> ATTITUDE; airspeed_validated -> VFR_HUD (the airspeed alone);
actuator_outputs -> SERVO_OUTPUT_RAW (a log with normalised outputs only has none to send);
vehicle_local_position -> LOCAL_POSITION_NED; wind (older PX4: wind_estimate) -> WIND_COV; a
HEARTBEAT (PX4, AUTO.MISSION) every second.

Boot time: a message's time in the log (for ALFA its header stamp, else when it was logged)
from the log's start (the instant screen_logs.py counts from), plus the whole seconds of
boot_at_start_s. The autopilot's grid of boot time is then the log's grid, so that the
samples made on either can be compared one for one.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from uav_fault_estimator.flight_logs.axes import (
    body_rates_frd,
    euler_from_quaternions,
    world_vectors_ned,
)
from uav_fault_estimator.flight_logs.csv_logs import TopicRows, log_start_ns, read_topic_rows
from uav_fault_estimator.flight_logs.readers import LOG_KINDS, log_format
from uav_fault_estimator.flight_logs.streams import AIRSPEED, ATTITUDE, BODY_RATES, OUTPUTS
from uav_fault_estimator.flight_logs.topics import MAVROS_TOPICS
from uav_fault_estimator.flight_logs.ulog import open_ulog, read_ulog, topic_data

from uav_mavlink.autopilot_emulator import (
    HEARTBEAT_HZ,
    attitude_message,
    heartbeat_message,
    local_position_ned_message,
    nav_controller_output_message,
    position_target_velocity_message,
    raw_imu_message,
    servo_output_raw_message,
    vfr_hud_message,
    wind_cov_message,
    wind_message,
)
from uav_mavlink.stream_rates import ARDUPILOT, PX4

BOOT_AT_START_S = 60  # the autopilot's boot time at the log's start, by default [whole s]
NANOSECONDS_PER_SECOND = 1_000_000_000
_XYZ, _WXYZ = tuple("xyz"), tuple("wxyz")
_LOCAL_POSITION, _WIND_TOPICS = "vehicle_local_position", ("wind", "wind_estimate")


@dataclass(frozen=True)
class TimedMessage:
    """A message (pymavlink's) and the autopilot's boot time it was sent at [s]."""

    boot_time_s: float
    message: Any


def log_messages(path: Path, boot_at_start_s: int = BOOT_AT_START_S) -> list[TimedMessage]:
    """The messages of the log at path (an ALFA flight folder or a PX4 .ulg), in time order
    (stable: messages of one instant in the order the module's docstring lists them).
    ValueError (one line naming the path) for anything else."""
    path = Path(path)
    kind = log_format(path)
    if kind == "csv":
        return alfa_messages(path, boot_at_start_s)
    if kind == "ulog":
        return ulog_messages(path, boot_at_start_s)
    raise ValueError(f"{path}: not a log whose messages can be played (expected an ALFA "
                     "flight folder of per-topic CSV files or a PX4 .ulg; "
                     f"screen_logs.py reads {LOG_KINDS})" if path.exists()
                     else f"{path}: no such file or folder")


def _in_time_order(messages: Iterable[TimedMessage], stack: str) -> list[TimedMessage]:
    """messages sorted by boot time (stable), a heartbeat of the stack every 1/HEARTBEAT_HZ
    from the first on."""
    ordered = sorted(messages, key=lambda timed: timed.boot_time_s)
    if not ordered:
        return []
    first_s, last_s = ordered[0].boot_time_s, ordered[-1].boot_time_s
    beats = [TimedMessage(first_s + k / HEARTBEAT_HZ, heartbeat_message(stack))
             for k in range(math.floor((last_s - first_s) * HEARTBEAT_HZ) + 1)]
    return sorted(beats + ordered, key=lambda timed: timed.boot_time_s)  # beats first


# ---- ALFA (ArduPlane through MAVROS) --------------------------------------------------------

# Per topic: the fields read, and rows -> (boot time [s], message) for each row
_ALFA_FIELDS: dict[str, tuple[str, ...]] = {
    "/mavros/imu/data": tuple(f"orientation.{axis}" for axis in _WXYZ)
    + tuple(f"angular_velocity.{axis}" for axis in _XYZ),
    "/mavros/imu/data_raw": tuple(f"angular_velocity.{axis}" for axis in _XYZ)
    + tuple(f"linear_acceleration.{axis}" for axis in _XYZ),
    "/mavros/rc/out": ("channels",),
    "/mavros/vfr_hud": ("airspeed", "groundspeed", "heading", "throttle", "altitude", "climb"),
    "/mavros/local_position/velocity": tuple(f"twist.linear.{axis}" for axis in _XYZ),
    "/mavros/wind_estimation": tuple(f"twist.linear.{axis}" for axis in _XYZ),
    "/mavros/nav_info/roll": ("commanded",),
    "/mavros/nav_info/pitch": ("commanded",),
    "/mavros/nav_info/velocity": ("des_x", "des_y", "des_z"),
}


def alfa_messages(folder: Path, boot_at_start_s: int = BOOT_AT_START_S) -> list[TimedMessage]:
    """The messages ArduPlane sent for an ALFA flight folder (the module's docstring), in
    time order. ValueError (one line naming the file) for a file the readers refuse."""
    rows = {topic: read_topic_rows(folder, topic, fields, ("channels",))
            for topic, fields in _ALFA_FIELDS.items()}
    # the log's start, as screen_logs.py counts: every topic it reads, its own ones too
    starts = [read_topic_rows(folder, topic) for topic in MAVROS_TOPICS
              if topic not in _ALFA_FIELDS]
    read = [found for found in (*rows.values(), *starts) if found is not None]
    start_ns = log_start_ns([found.log_times_ns for found in read],
                            [found.stamps_ns for found in read])

    def boot_s(found: TopicRows) -> np.ndarray:
        return _boot_times_s(found.times_ns - start_ns, boot_at_start_s)

    messages = []
    for topic, pack in _ALFA_PACKERS.items():
        if rows[topic] is not None:
            messages += pack(rows[topic], boot_s(rows[topic]))
    roll, pitch = rows["/mavros/nav_info/roll"], rows["/mavros/nav_info/pitch"]
    if roll is not None and pitch is not None:
        messages += _nav_controller_outputs(roll, pitch, boot_s(roll), boot_s(pitch))
    return _in_time_order(messages, ARDUPILOT)


def _boot_times_s(since_start_ns: np.ndarray, boot_at_start_s: int) -> np.ndarray:
    """Times since the log's start [ns] as boot times [s]: plus whole seconds, so that
    multiples of any period dividing a second stay multiples."""
    return (since_start_ns + int(boot_at_start_s) * NANOSECONDS_PER_SECOND) * 1e-9


def _columns(found: TopicRows, names: tuple[str, ...]) -> np.ndarray:
    return np.column_stack([found.fields[name] for name in names])


def _attitudes(found: TopicRows, boot_s: np.ndarray) -> list[TimedMessage]:
    names = _ALFA_FIELDS["/mavros/imu/data"]
    euler = euler_from_quaternions(_columns(found, names[:4]), "FLU")
    rates = body_rates_frd(_columns(found, names[4:]), "FLU")
    return [TimedMessage(t, attitude_message(t, e, r))
            for t, e, r in zip(boot_s, euler, rates, strict=True) if np.isfinite(e).all()]


def _raw_imus(found: TopicRows, boot_s: np.ndarray) -> list[TimedMessage]:
    names = _ALFA_FIELDS["/mavros/imu/data_raw"]
    rates = body_rates_frd(_columns(found, names[:3]), "FLU")
    forces = body_rates_frd(_columns(found, names[3:]), "FLU")  # a body vector: same swap
    return [TimedMessage(t, raw_imu_message(t, r, f))
            for t, r, f in zip(boot_s, rates, forces, strict=True)]


def _servo_outputs(found: TopicRows, boot_s: np.ndarray) -> list[TimedMessage]:
    return [TimedMessage(t, servo_output_raw_message(t, channels))
            for t, channels in zip(boot_s, found.fields["channels"], strict=True)]


def _vfr_huds(found: TopicRows, boot_s: np.ndarray) -> list[TimedMessage]:
    values = _columns(found, _ALFA_FIELDS["/mavros/vfr_hud"])
    return [TimedMessage(t, vfr_hud_message(*row)) for t, row in zip(boot_s, values,
                                                                       strict=True)]


def _local_positions(found: TopicRows, boot_s: np.ndarray) -> list[TimedMessage]:
    velocity = world_vectors_ned(_columns(found, _ALFA_FIELDS["/mavros/local_position/"
                                                               "velocity"]), "FLU")
    unknown = (math.nan,) * 3
    return [TimedMessage(t, local_position_ned_message(t, unknown, v))
            for t, v in zip(boot_s, velocity, strict=True)]


def _winds(found: TopicRows, boot_s: np.ndarray) -> list[TimedMessage]:
    wind = world_vectors_ned(_columns(found, _ALFA_FIELDS["/mavros/wind_estimation"]), "FLU")
    return [TimedMessage(t, wind_message(w)) for t, w in zip(boot_s, wind, strict=True)]


def _position_targets(found: TopicRows, boot_s: np.ndarray) -> list[TimedMessage]:
    velocity = _columns(found, _ALFA_FIELDS["/mavros/nav_info/velocity"])  # NED already
    return [TimedMessage(t, position_target_velocity_message(t, v))
            for t, v in zip(boot_s, velocity, strict=True)]


def _nav_controller_outputs(roll: TopicRows, pitch: TopicRows, roll_boot_s: np.ndarray,
                            pitch_boot_s: np.ndarray) -> list[TimedMessage]:
    """One NAV_CONTROLLER_OUTPUT per roll row [deg], with the pitch row nearest it in time."""
    nearest = _nearest(pitch_boot_s, roll_boot_s)
    pitch_deg = pitch.fields["commanded"][nearest]
    return [TimedMessage(t, nav_controller_output_message(math.radians(r), math.radians(p)))
            for t, r, p in zip(roll_boot_s, roll.fields["commanded"], pitch_deg, strict=True)]


def _nearest(times_s: np.ndarray, at_s: np.ndarray) -> np.ndarray:
    """The index in times_s (ordered) of the time nearest each of at_s."""
    right = np.clip(np.searchsorted(times_s, at_s), 1, times_s.size - 1)
    left = right - 1
    return np.where(np.abs(times_s[left] - at_s) <= np.abs(times_s[right] - at_s), left,
                    right) if times_s.size > 1 else np.zeros(at_s.size, dtype=int)


_ALFA_PACKERS: dict[str, Callable[[TopicRows, np.ndarray], list[TimedMessage]]] = {
    "/mavros/imu/data": _attitudes,
    "/mavros/imu/data_raw": _raw_imus,
    "/mavros/rc/out": _servo_outputs,
    "/mavros/vfr_hud": _vfr_huds,
    "/mavros/local_position/velocity": _local_positions,
    "/mavros/wind_estimation": _winds,
    "/mavros/nav_info/velocity": _position_targets,
}


# ---- PX4 ULog -------------------------------------------------------------------------------

def ulog_messages(path: Path, boot_at_start_s: int = BOOT_AT_START_S) -> list[TimedMessage]:
    """The messages PX4 streamed for a ULog (the module's docstring), in time order.
    ValueError (one line naming the file) for a file that is not a readable ULog."""
    log = read_ulog(Path(path))
    streams = log.streams
    messages = []
    if ATTITUDE in streams:
        attitude = streams[ATTITUDE]
        rates = (_held(streams[BODY_RATES].times_s, streams[BODY_RATES].values,
                       attitude.times_s) if BODY_RATES in streams
                 else np.full((attitude.times_s.size, 3), math.nan))
        messages += [TimedMessage(t + boot_at_start_s, attitude_message(t + boot_at_start_s,
                                                                         e, r))
                     for t, e, r in zip(attitude.times_s, attitude.values, rates, strict=True)]
    if AIRSPEED in streams:
        nan = math.nan
        messages += [TimedMessage(t + boot_at_start_s, vfr_hud_message(v, nan, 0.0, 0.0, nan,
                                                                        nan))
                     for t, (v,) in zip(streams[AIRSPEED].times_s, streams[AIRSPEED].values,
                                        strict=True)]
    if OUTPUTS in streams and log.output_unit == "pwm_us":
        outputs = streams[OUTPUTS]
        messages += [TimedMessage(t + boot_at_start_s,
                                  servo_output_raw_message(t + boot_at_start_s, pwm))
                     for t, pwm in zip(outputs.times_s, outputs.values, strict=True)]
    ulog = open_ulog(Path(path), (_LOCAL_POSITION, *_WIND_TOPICS))
    messages += _px4_positions_and_winds(topic_data(ulog), ulog.start_timestamp,
                                         boot_at_start_s)
    return _in_time_order(messages, PX4)


def _held(times_s: np.ndarray, values: np.ndarray, at_s: np.ndarray) -> np.ndarray:
    """values (n, k) at times_s: the last at or before each of at_s (NaN before the first)."""
    index = np.searchsorted(times_s, at_s, side="right") - 1
    held = values[np.clip(index, 0, None)].astype(float)
    held[index < 0] = math.nan
    return held


def _px4_positions_and_winds(data: dict[str, dict], start_us: int,
                             boot_at_start_s: int) -> list[TimedMessage]:
    """LOCAL_POSITION_NED of vehicle_local_position and WIND_COV of the wind topic."""
    messages = []

    def boot_s(topic: dict) -> np.ndarray:
        return (topic["timestamp"].astype(np.int64) - np.int64(start_us)) * 1e-6 \
            + boot_at_start_s

    if _LOCAL_POSITION in data:
        topic = data[_LOCAL_POSITION]
        position = np.column_stack([topic[name] for name in ("x", "y", "z")])
        velocity = np.column_stack([topic[name] for name in ("vx", "vy", "vz")])
        messages += [TimedMessage(t, local_position_ned_message(t, p, v))
                     for t, p, v in zip(boot_s(topic), position, velocity, strict=True)]
    wind_topic = next((name for name in _WIND_TOPICS if name in data), None)
    if wind_topic is not None:
        topic = data[wind_topic]
        wind = np.column_stack([topic["windspeed_north"], topic["windspeed_east"],
                                np.zeros(topic["timestamp"].size)])
        messages += [TimedMessage(t, wind_cov_message(t, w, math.nan))
                     for t, w in zip(boot_s(topic), wind, strict=True)]
    return messages
