"""Rotations between the local North-East-Down frame and body axes; positions north and
east of an origin; the specific force an accelerometer reads."""

from __future__ import annotations

import numpy as np

GRAVITY_MPS2 = 9.80665  # standard gravity, down in NED


def ned_to_body(roll_rad: float, pitch_rad: float, yaw_rad: float) -> np.ndarray:
    """Direction cosine matrix C_bn (3x3): x_body = C_bn @ x_ned, ZYX Euler angles."""
    cr, sr = np.cos(roll_rad), np.sin(roll_rad)
    cp, sp = np.cos(pitch_rad), np.sin(pitch_rad)
    cy, sy = np.cos(yaw_rad), np.sin(yaw_rad)
    return np.array(
        [
            [cp * cy, cp * sy, -sp],
            [sr * sp * cy - cr * sy, sr * sp * sy + cr * cy, sr * cp],
            [cr * sp * cy + sr * sy, cr * sp * sy - sr * cy, cr * cp],
        ]
    )


def specific_force_body_mps2(acceleration_ned_mps2: np.ndarray, roll_rad: float,
                             pitch_rad: float, yaw_rad: float) -> np.ndarray:
    """The specific force in body axes FRD [m/s^2], an accelerometer's reading (-g along z
    at rest): C_bn (a - g) for the NED acceleration a [m/s^2]."""
    gravity_ned = np.array([0.0, 0.0, GRAVITY_MPS2])
    return ned_to_body(roll_rad, pitch_rad, yaw_rad) @ (acceleration_ned_mps2 - gravity_ned)


def air_velocity_body_mps(airspeed_mps, angle_of_attack_rad, sideslip_rad) -> np.ndarray:
    """Air-relative velocity in body axes [m/s] from airspeed, alpha and beta:
    V (cos a cos b, sin b, sin a cos b)."""
    cos_beta = np.cos(sideslip_rad)
    return airspeed_mps * np.array([np.cos(angle_of_attack_rad) * cos_beta, np.sin(sideslip_rad),
                                    np.sin(angle_of_attack_rad) * cos_beta])


def wind_triangle_ned_mps(velocity_ned_mps: np.ndarray, roll_rad: float, pitch_rad: float,
                          yaw_rad: float, air_data: np.ndarray) -> np.ndarray:
    """The wind [m/s, NED, towards] from the wind triangle: ground velocity less the air
    velocity, air_data = (true airspeed [m/s], angle of attack, sideslip [rad])."""
    body_to_ned = ned_to_body(roll_rad, pitch_rad, yaw_rad).T
    return velocity_ned_mps - body_to_ned @ air_velocity_body_mps(*air_data)


EARTH_RADIUS_M = 6378137.0  # WGS-84 equatorial; the flat-earth map spans a few km


def north_east_m(latitude_rad, longitude_rad, origin_rad: tuple[float, float]) -> np.ndarray:
    """Flat-earth north and east [m] of origin_rad (latitude, longitude) for scalars or
    arrays of latitude and longitude [rad]; shape (2,) + the inputs' shape."""
    latitude0, longitude0 = origin_rad
    north = (np.asarray(latitude_rad) - latitude0) * EARTH_RADIUS_M
    east = (np.asarray(longitude_rad) - longitude0) * EARTH_RADIUS_M * np.cos(latitude0)
    return np.array([north, east])
