"""The project's messages built from the core's numpy arrays (ROS message types, no
node). Their fields are read back by uav_common.message_fields."""

from __future__ import annotations

from collections.abc import Sequence

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Vector3, Vector3Stamped
from std_msgs.msg import Header
from uav_fault_msgs.msg import (
    AircraftState,
    AirData,
    AutopilotSetpoints,
    ControlInputs,
    FaultVector,
    WindEstimate,
)

from uav_common.channels import AIR_DATA_FIELDS, SETPOINT_FIELDS
from uav_common.message_fields import CONTROL_FIELDS, STATE_FIELDS
from uav_common.sample_grid import NANOSECONDS_PER_SECOND

# Frame ids (REP 103 allows NED and FRD with suffixed names; REP 105's map and base_link):
# the local North-East-Down frame, and the airframe's Forward-Right-Down body axes.
NED_FRAME = "map_ned"
BODY_FRAME = "base_link_frd"


def stamp(time_s: float) -> Time:
    """A ROS time from seconds of simulation time (rounded to the nanosecond)."""
    return stamp_from_nanoseconds(round(time_s * NANOSECONDS_PER_SECOND))


def stamp_from_nanoseconds(time_ns: int) -> Time:
    """A ROS time from integer nanoseconds: exact where a float of seconds since 1970 would
    resolve only 0.24 us."""
    seconds, nanoseconds = divmod(time_ns, NANOSECONDS_PER_SECOND)
    return Time(sec=int(seconds), nanosec=int(nanoseconds))


def header(time_s: float, frame_id: str = "") -> Header:
    return Header(stamp=stamp(time_s), frame_id=frame_id)


def _filled(message, fields: Sequence[str], values: Sequence[float]):
    """message with each of fields set to its value as a float."""
    for field, value in zip(fields, values, strict=True):
        setattr(message, field, float(value))
    return message


def state_message(time_s: float, state: Sequence[float]) -> AircraftState:
    """AircraftState from a (14,) array in STATE_CHANNELS order (NaN: channel missing)."""
    return _filled(AircraftState(header=header(time_s, NED_FRAME)), STATE_FIELDS, state)


def controls_message(time_s: float, controls: Sequence[float]) -> ControlInputs:
    """ControlInputs from a (7,) array in CONTROL_CHANNELS order (ignition: nonzero is on)."""
    message = ControlInputs(header=header(time_s))
    for field, value in zip(CONTROL_FIELDS, controls, strict=True):
        setattr(message, field, bool(value) if field == "ignition" else float(value))
    return message


def air_data_message(time_s: float, air_data: Sequence[float]) -> AirData:
    """AirData from a (3,) array in AIR_DATA_CHANNELS order (NaN: channel missing)."""
    return _filled(AirData(header=header(time_s, BODY_FRAME)), AIR_DATA_FIELDS, air_data)


def setpoints_message(time_s: float, setpoints: Sequence[float]) -> AutopilotSetpoints:
    """AutopilotSetpoints from a (3,) array in SETPOINT_FIELDS order (NaN: not known)."""
    return _filled(AutopilotSetpoints(header=header(time_s, NED_FRAME)), SETPOINT_FIELDS,
                   setpoints)


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


def fault_vector_message(
    time_s: float, names: Sequence[str], values_pct: Sequence[float]
) -> FaultVector:
    return FaultVector(
        header=header(time_s), names=list(names), values_pct=[float(v) for v in values_pct]
    )
