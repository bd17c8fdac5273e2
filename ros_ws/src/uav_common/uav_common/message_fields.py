"""The project's messages read into the core's numpy arrays, without ROS: the functions take
any object with the message's fields (an rclpy message, or one rosbags deserialised from a
recording), so that reporting and analysis run without rclpy.

Field names come from uav_common.channels, so the order of an array is the order of its
channel tuple and a message field is ``<channel>_<unit>``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from uav_common.channels import (
    AIR_DATA_FIELDS,
    CONTROL_CHANNELS,
    CONTROL_UNITS,
    SETPOINT_FIELDS,
    STATE_CHANNELS,
    STATE_UNITS,
    field_name,
)
from uav_common.sample_grid import NANOSECONDS_PER_SECOND

STATE_FIELDS = tuple(map(field_name, STATE_CHANNELS, STATE_UNITS))
CONTROL_FIELDS = tuple(map(field_name, CONTROL_CHANNELS, CONTROL_UNITS))


class Stamp(Protocol):
    """builtin_interfaces/Time's fields."""

    sec: int
    nanosec: int


def stamp_seconds(time: Stamp) -> float:
    """Seconds from a ROS time."""
    return time.sec + time.nanosec / NANOSECONDS_PER_SECOND


def stamp_nanoseconds(time: Stamp) -> int:
    """Nanoseconds from a ROS time: exact, for matching stamps."""
    return time.sec * NANOSECONDS_PER_SECOND + time.nanosec


def _values(message: Any, fields: Sequence[str]) -> np.ndarray:
    return np.array([getattr(message, field) for field in fields], dtype=float)


def state_array(message: Any) -> np.ndarray:
    """(14,) array in STATE_CHANNELS order from an AircraftState."""
    return _values(message, STATE_FIELDS)


def controls_array(message: Any) -> np.ndarray:
    """(7,) array in CONTROL_CHANNELS order from ControlInputs (ignition as 0.0 or 1.0)."""
    return np.array([float(getattr(message, field)) for field in CONTROL_FIELDS])


def air_data_array(message: Any) -> np.ndarray:
    """(3,) array in AIR_DATA_CHANNELS order from an AirData message."""
    return _values(message, AIR_DATA_FIELDS)


def setpoints_array(message: Any) -> np.ndarray:
    """(3,) array in SETPOINT_FIELDS order from an AutopilotSetpoints message."""
    return _values(message, SETPOINT_FIELDS)


def wind_array(message: Any) -> np.ndarray:
    """(3,) NED wind [m/s] from a WindEstimate."""
    return np.array([message.north_mps, message.east_mps, message.down_mps])


def true_wind_array(message: Any) -> np.ndarray:
    """(3,) NED wind [m/s] from a geometry_msgs/Vector3Stamped (sim_node's wind/true)."""
    return np.array([message.vector.x, message.vector.y, message.vector.z])
