"""The aircraft's state in ROS's standard frames (REP 103, REP 105), without ROS.

The project's AircraftState holds the geodetic position, the ZYX Euler attitude of the body
axes FRD (x forward, y right, z down) in the local North-East-Down frame, the NED ground
velocity and the FRD body rates. ROS tools (RViz, Foxglove, tf2) expect a world frame `map`
East-North-Up and a body frame `base_link` forward-left-up (FLU):

    position        ENU [m] of the geodetic position about the map's origin (WGS-84)
    orientation     R_map_base = R_enu_ned C_nb(yaw, pitch, roll) R_frd_flu, as a quaternion
    velocity        in base_link: R_flu_frd C_bn v_ned
    angular rates   in base_link: (p, -q, -r)
    specific force  in base_link: R_flu_frd C_bn (dv_ned/dt - g_ned), an accelerometer's
                    reading (+g up at rest), dv/dt differenced from consecutive states: the
                    state carries no acceleration, so it is as noisy as the velocity's steps

Altitude is the state's (above mean sea level); the map's height is taken as the ellipsoid's
(the simulator models no geoid, and the map spans a few km).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pymap3d
from scipy.spatial.transform import Rotation
from uav_aircraft.frames import ned_to_body, specific_force_body_mps2
from uav_common.channels import state_indices

ENU_FROM_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
FLU_FROM_FRD = np.diag([1.0, -1.0, -1.0])  # its own inverse

POSITION = state_indices("latitude", "longitude", "altitude")
ATTITUDE = state_indices("roll", "pitch", "yaw")
VELOCITY_NED = state_indices("velocity_north", "velocity_east", "velocity_down")
BODY_RATES = state_indices("roll_rate", "pitch_rate", "yaw_rate")


@dataclass(frozen=True)
class GeodeticPoint:
    """A WGS-84 point: latitude and longitude [deg], altitude [m]."""

    latitude_deg: float
    longitude_deg: float
    altitude_m: float


@dataclass(frozen=True)
class StandardState:
    """One state in REP 103 frames; an entry is NaN where the state's channels it needs are
    missing (and the specific force for the first state and after a reset)."""

    time_s: float
    position: GeodeticPoint
    position_enu_m: np.ndarray  # (3,) base_link's origin in map
    orientation_xyzw: np.ndarray  # (4,) base_link in map, unit quaternion (x, y, z, w)
    velocity_flu_mps: np.ndarray  # (3,) ground velocity in base_link
    angular_velocity_flu_radps: np.ndarray  # (3,)
    specific_force_flu_mps2: np.ndarray  # (3,)


def position_enu_m(point: GeodeticPoint, origin: GeodeticPoint) -> np.ndarray:
    """East, north, up [m] of point from origin, on the WGS-84 ellipsoid."""
    return np.array(pymap3d.geodetic2enu(point.latitude_deg, point.longitude_deg,
                                         point.altitude_m, origin.latitude_deg,
                                         origin.longitude_deg, origin.altitude_m))


def orientation_xyzw(roll_rad: float, pitch_rad: float, yaw_rad: float) -> np.ndarray:
    """The quaternion (x, y, z, w) of base_link (FLU) in map (ENU) for a ZYX Euler attitude
    of the FRD body axes in NED; NaN for a non-finite attitude."""
    if not all(map(math.isfinite, (roll_rad, pitch_rad, yaw_rad))):
        return np.full(4, np.nan)
    body_to_ned = ned_to_body(roll_rad, pitch_rad, yaw_rad).T
    return Rotation.from_matrix(ENU_FROM_NED @ body_to_ned @ FLU_FROM_FRD).as_quat()


def flu_from_ned(vector_ned: np.ndarray, attitude_rad: np.ndarray) -> np.ndarray:
    """A NED vector expressed in base_link (FLU) at the given (roll, pitch, yaw) [rad]."""
    return FLU_FROM_FRD @ ned_to_body(*attitude_rad) @ vector_ned


class StandardFrames:
    """AircraftState arrays into StandardState, one after the other (the specific force is
    differenced from the previous state). The map's origin is the one given, else the first
    state with a finite position."""

    def __init__(self, origin: GeodeticPoint | None = None) -> None:
        self.origin = origin
        self._previous: tuple[float, np.ndarray] | None = None  # time [s], NED velocity

    def reset(self) -> None:
        """Forget the previous state (a source restarted): no difference across it."""
        self._previous = None

    def update(self, time_s: float, state: np.ndarray) -> StandardState:
        """The state (STATE_CHANNELS order, SI units) at time_s [s] in REP 103 frames."""
        latitude_rad, longitude_rad, altitude_m = state[POSITION]
        point = GeodeticPoint(math.degrees(latitude_rad), math.degrees(longitude_rad),
                              float(altitude_m))
        if self.origin is None and np.isfinite(state[POSITION]).all():
            self.origin = point
        position = (position_enu_m(point, self.origin) if self.origin is not None
                    else np.full(3, np.nan))
        attitude, velocity_ned = state[ATTITUDE], state[VELOCITY_NED]
        return StandardState(
            time_s=time_s, position=point, position_enu_m=position,
            orientation_xyzw=orientation_xyzw(*attitude),
            velocity_flu_mps=flu_from_ned(velocity_ned, attitude),
            angular_velocity_flu_radps=FLU_FROM_FRD @ state[BODY_RATES],
            specific_force_flu_mps2=self._specific_force(time_s, velocity_ned, attitude))

    def _specific_force(self, time_s: float, velocity_ned: np.ndarray,
                        attitude_rad: np.ndarray) -> np.ndarray:
        previous, self._previous = self._previous, (time_s, velocity_ned.copy())
        if previous is None or time_s <= previous[0]:
            return np.full(3, np.nan)
        acceleration_ned = (velocity_ned - previous[1]) / (time_s - previous[0])
        return FLU_FROM_FRD @ specific_force_body_mps2(acceleration_ned, *attitude_rad)
