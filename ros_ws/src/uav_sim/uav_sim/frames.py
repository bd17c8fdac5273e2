"""Rotations between the local North-East-Down frame and body axes."""

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
