"""Body axes of flight logs: the one home of the FLU -> FRD conversion.

A log's convention is "FRD" (body Forward-Right-Down, attitude from North-East-Down: PX4,
the project) or "FLU" (body Forward-Left-Up, attitude from East-North-Up: ROS's REP 103, so
MAVROS). The streams are always FRD/NED (streams.py). Both axis swaps are their own
inverses, so the same functions also turn FRD values into FLU ones (the test logs' writers).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation
from uav_aircraft.airframe import AXES

# FLU <-> FRD: y and z reversed. ENU <-> NED: x and y exchanged, z reversed.
_BODY_SWAP = np.diag([1.0, -1.0, -1.0])
_WORLD_SWAP = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def checked_axes(axes: str) -> str:
    """axes when it is one of AXES; ValueError otherwise."""
    if axes not in AXES:
        raise ValueError(f"axes {axes!r}: expected one of {', '.join(AXES)}")
    return axes


def body_rates_frd(rates_radps: np.ndarray, axes: str) -> np.ndarray:
    """Body rates (n, 3) [rad/s] about the log's axes -> p, q, r (n, 3) about FRD."""
    return rates_radps @ _BODY_SWAP if checked_axes(axes) == "FLU" else rates_radps


def world_vectors_ned(vectors: np.ndarray, axes: str) -> np.ndarray:
    """Vectors (n, 3) in the log's world frame (ENU for FLU logs, NED for FRD) -> NED."""
    return vectors @ _WORLD_SWAP if checked_axes(axes) == "FLU" else vectors


def euler_from_quaternions(quaternions_wxyz: np.ndarray, axes: str) -> np.ndarray:
    """Attitude quaternions (n, 4), scalar first, rotating the log's body axes into its world
    frame -> roll, pitch, yaw (n, 3) [rad] of FRD from NED (yaw in (-pi, pi]). Rows that are
    not finite or of zero norm give NaN."""
    quaternions = np.asarray(quaternions_wxyz, dtype=float).reshape(-1, 4)
    euler = np.full((quaternions.shape[0], 3), np.nan)
    norms = np.linalg.norm(quaternions, axis=1)
    valid = np.isfinite(norms) & (norms > 0)
    if valid.any():
        matrices = Rotation.from_quat(quaternions[valid], scalar_first=True).as_matrix()
        euler[valid] = _euler_ned_frd(_swapped(matrices, axes))
    return euler


def euler_frd(euler_rad: np.ndarray, axes: str) -> np.ndarray:
    """Roll, pitch, yaw (n, 3) [rad] of the log's body from its world frame -> of FRD from
    NED (yaw in (-pi, pi])."""
    if checked_axes(axes) == "FRD":
        return euler_rad
    return _euler_ned_frd(_swapped(_matrices(euler_rad), axes))


def quaternions_from_euler(euler_frd_rad: np.ndarray, axes: str) -> np.ndarray:
    """Roll, pitch, yaw (n, 3) [rad] of FRD from NED -> quaternions (n, 4), scalar first,
    rotating the axes' body into their world frame: what a log of that convention holds."""
    matrices = _swapped(_matrices(euler_frd_rad), axes)
    return Rotation.from_matrix(matrices).as_quat(scalar_first=True)


def _matrices(euler_rad: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3), body to world, of roll, pitch, yaw (n, 3) (ZYX)."""
    return Rotation.from_euler("ZYX", np.asarray(euler_rad)[:, ::-1]).as_matrix()


def _swapped(matrices: np.ndarray, axes: str) -> np.ndarray:
    """Body-to-world rotation matrices in the log's axes -> in FRD/NED (and back)."""
    if checked_axes(axes) == "FRD":
        return matrices
    return _WORLD_SWAP @ matrices @ _BODY_SWAP


def _euler_ned_frd(matrices: np.ndarray) -> np.ndarray:
    """roll, pitch, yaw (n, 3) [rad] of body-to-world rotation matrices (ZYX)."""
    return Rotation.from_matrix(matrices).as_euler("ZYX")[:, ::-1]
