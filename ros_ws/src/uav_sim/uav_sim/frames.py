"""Rotations between the local North-East-Down frame and body axes; positions north and
east of an origin."""

from __future__ import annotations

import numpy as np


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


EARTH_RADIUS_M = 6378137.0  # WGS-84 equatorial; the flat-earth map spans a few km


def north_east_m(latitude_rad, longitude_rad, origin_rad: tuple[float, float]) -> np.ndarray:
    """Flat-earth north and east [m] of origin_rad (latitude, longitude) for scalars or
    arrays of latitude and longitude [rad]; shape (2,) + the inputs' shape."""
    latitude0, longitude0 = origin_rad
    north = (np.asarray(latitude_rad) - latitude0) * EARTH_RADIUS_M
    east = (np.asarray(longitude_rad) - longitude0) * EARTH_RADIUS_M * np.cos(latitude0)
    return np.array([north, east])
