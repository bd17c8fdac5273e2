"""Conversions between the core's numpy arrays and the project's messages (no rclpy).

Field names come from uav_sim.channels, so the order of an array is the order of its
channel tuple and a message field is ``<channel>_<unit>``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Vector3, Vector3Stamped
from std_msgs.msg import Header
from uav_fault_msgs.msg import AircraftState, AirData, ControlInputs, FaultVector, WindEstimate

from uav_sim.channels import (
    AIR_DATA_FIELDS,
    CONTROL_CHANNELS,
    CONTROL_UNITS,
    STATE_CHANNELS,
    STATE_UNITS,
    field_name,
)
from uav_sim.sample_grid import NANOSECONDS_PER_SECOND

# Frame ids (REP 103 allows NED and FRD with suffixed names; REP 105's map and base_link):
# the local North-East-Down frame, and the airframe's Forward-Right-Down body axes.
NED_FRAME = "map_ned"
BODY_FRAME = "base_link_frd"
STATE_FIELDS = tuple(map(field_name, STATE_CHANNELS, STATE_UNITS))
CONTROL_FIELDS = tuple(map(field_name, CONTROL_CHANNELS, CONTROL_UNITS))


def stamp(time_s: float) -> Time:
    """A ROS time from seconds of simulation time (rounded to the nanosecond)."""
    seconds, nanoseconds = divmod(round(time_s * NANOSECONDS_PER_SECOND), NANOSECONDS_PER_SECOND)
    return Time(sec=int(seconds), nanosec=int(nanoseconds))


def stamp_seconds(time: Time) -> float:
    """Seconds from a ROS time."""
    return time.sec + time.nanosec / NANOSECONDS_PER_SECOND


def stamp_nanoseconds(time: Time) -> int:
    """Nanoseconds from a ROS time: exact, for matching stamps."""
    return time.sec * NANOSECONDS_PER_SECOND + time.nanosec


def header(time_s: float, frame_id: str = "") -> Header:
    return Header(stamp=stamp(time_s), frame_id=frame_id)


def _filled(message, fields: Sequence[str], values: Sequence[float]):
    """message with each of fields set to its value as a float."""
    for field, value in zip(fields, values, strict=True):
        setattr(message, field, float(value))
    return message


def _values(message, fields: Sequence[str]) -> np.ndarray:
    return np.array([getattr(message, field) for field in fields], dtype=float)


def state_message(time_s: float, state: Sequence[float]) -> AircraftState:
    """AircraftState from a (14,) array in STATE_CHANNELS order (NaN: channel missing)."""
    return _filled(AircraftState(header=header(time_s, NED_FRAME)), STATE_FIELDS, state)


def state_array(message: AircraftState) -> np.ndarray:
    """(14,) array in STATE_CHANNELS order from an AircraftState."""
    return _values(message, STATE_FIELDS)


def controls_message(time_s: float, controls: Sequence[float]) -> ControlInputs:
    """ControlInputs from a (7,) array in CONTROL_CHANNELS order (ignition: nonzero is on)."""
    message = ControlInputs(header=header(time_s))
    for field, value in zip(CONTROL_FIELDS, controls, strict=True):
        setattr(message, field, bool(value) if field == "ignition" else float(value))
    return message


def controls_array(message: ControlInputs) -> np.ndarray:
    """(7,) array in CONTROL_CHANNELS order from ControlInputs (ignition as 0.0 or 1.0)."""
    return np.array([float(getattr(message, field)) for field in CONTROL_FIELDS])


def air_data_message(time_s: float, air_data: Sequence[float]) -> AirData:
    """AirData from a (3,) array in AIR_DATA_CHANNELS order (NaN: channel missing)."""
    return _filled(AirData(header=header(time_s, BODY_FRAME)), AIR_DATA_FIELDS, air_data)


def air_data_array(message: AirData) -> np.ndarray:
    """(3,) array in AIR_DATA_CHANNELS order from an AirData message."""
    return _values(message, AIR_DATA_FIELDS)


def wind_message(time_s: float, wind_ned_mps: Sequence[float], tau_s: float) -> WindEstimate:
    north, east, down = (float(value) for value in wind_ned_mps)
    return WindEstimate(
        header=header(time_s, NED_FRAME),
        north_mps=north,
        east_mps=east,
        down_mps=down,
        filter_time_constant_s=float(tau_s),
    )


def true_wind_message(time_s: float, wind_ned_mps: Sequence[float]) -> Vector3Stamped:
    """The simulation's true wind (background plus turbulence), NED [m/s, towards]."""
    north, east, down = (float(value) for value in wind_ned_mps)
    return Vector3Stamped(header=header(time_s, NED_FRAME),
                          vector=Vector3(x=north, y=east, z=down))


def wind_array(message: WindEstimate) -> np.ndarray:
    """(3,) NED wind [m/s] from a WindEstimate."""
    return np.array([message.north_mps, message.east_mps, message.down_mps])


def fault_vector_message(
    time_s: float, names: Sequence[str], values_pct: Sequence[float]
) -> FaultVector:
    return FaultVector(
        header=header(time_s), names=list(names), values_pct=[float(v) for v in values_pct]
    )
