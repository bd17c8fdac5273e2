"""Synthetic air data: the flow angles and wind of an aircraft without vanes, from what its
residual models flew and the estimator's wind errors. No ROS here.

The models of a sample without vanes fly the pitot's airspeed V along the filtered wind's
air velocity (residuals.pitot_wind_ned_mps); the estimator's wind error e (NED, the unknown
of its window at the newest sample) corrects that wind, and the pitot keeps the magnitude:

    w = pitot_wind(v, w_flown + e, V),   V_body = C_bn (v - w),
    alpha = atan2(V_body_z, V_body_x),   beta = asin(V_body_y / V)

with v the ground velocity (w_flown + C_nb V_body,flown). Standard deviations carry e's
covariance through that map by its Jacobian (central differences).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from uav_aircraft.frames import ned_to_body

from uav_fault_estimator.estimation.residuals import pitot_wind_ned_mps

# Central-difference step of the Jacobian [m/s]: small against a gust, large against
# rounding
JACOBIAN_STEP_MPS = 1e-3


@dataclass(frozen=True)
class AirDataEstimate:
    """Synthetic air data (AirDataEstimate.msg): airspeed [m/s], angle of attack and
    sideslip [rad], wind (3,) [m/s, NED, towards], and their standard deviations."""

    true_airspeed_mps: float
    angle_of_attack_rad: float
    sideslip_rad: float
    wind_ned_mps: np.ndarray
    angle_of_attack_std_rad: float
    sideslip_std_rad: float
    wind_std_mps: np.ndarray


def _flow(velocity_ned_mps: np.ndarray, to_body: np.ndarray, wind_ned_mps: np.ndarray,
          airspeed_mps: float) -> np.ndarray:
    """(alpha, beta [rad], wind (3,) [m/s]) of a wind estimate given the pitot's airspeed."""
    wind = pitot_wind_ned_mps(velocity_ned_mps, wind_ned_mps, airspeed_mps)
    u, v, w = to_body @ (velocity_ned_mps - wind)
    return np.array([math.atan2(w, u), math.asin(max(-1.0, min(1.0, v / airspeed_mps))),
                     *wind])


def estimate_air_data(wind_flown_ned_mps: np.ndarray, air_velocity_body_mps: np.ndarray,
                      attitude_rad: np.ndarray, wind_error_ned_mps: np.ndarray,
                      wind_error_covariance: np.ndarray) -> AirDataEstimate:
    """The synthetic air data of one sample (module docstring).

    Inputs: the wind the models flew (3,) [m/s, NED], their air velocity (3,) [m/s, body
    axes], the attitude (roll, pitch, yaw) [rad]; the estimated wind error (3,) [m/s, NED]
    and its covariance (3, 3) [m²/s²].
    """
    to_body = ned_to_body(*attitude_rad)
    velocity = wind_flown_ned_mps + to_body.T @ air_velocity_body_mps
    airspeed = float(np.linalg.norm(air_velocity_body_mps))
    wind = wind_flown_ned_mps + wind_error_ned_mps
    flow = _flow(velocity, to_body, wind, airspeed)
    jacobian = np.column_stack([
        (_flow(velocity, to_body, wind + step, airspeed)
         - _flow(velocity, to_body, wind - step, airspeed)) / (2 * JACOBIAN_STEP_MPS)
        for step in JACOBIAN_STEP_MPS * np.eye(3)])
    deviation = np.sqrt(np.maximum(np.diag(jacobian @ wind_error_covariance @ jacobian.T), 0.0))
    return AirDataEstimate(airspeed, float(flow[0]), float(flow[1]), flow[2:],
                           float(deviation[0]), float(deviation[1]), deviation[2:])
