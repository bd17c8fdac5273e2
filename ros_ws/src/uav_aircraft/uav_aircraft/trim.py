"""Straight and level trim of a vehicle on JSBSim's own force and moment model.

JSBSim's trim (`simulation/do_simple_trim`) fails on these aircraft: its engine speed does
not respond to the throttle while JSBSim trims ("udot doesn't appear to be trimmable",
measured on jsbsim 1.3.3). So the trim solves udot = wdot = qdot = 0 for angle of attack,
elevator and throttle itself, evaluating JSBSim's accelerations with `run_ic()` and the
propeller at the speed where it absorbs the engine's power (uav_aircraft.propeller).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import jsbsim
import numpy as np
from scipy.optimize import root

from uav_aircraft.fdm import (
    EFFECTIVE_THROTTLE,
    JSBSIM_ENGINE_ON,
    KG_PER_M3_PER_SLUG_PER_FT3,
    M_PER_FT,
    apply_propeller_model,
    clear_propeller_model,
)
from uav_aircraft.frames import ned_to_body
from uav_aircraft.propeller import Propeller

if TYPE_CHECKING:
    from uav_aircraft.vehicles import Vehicle

TRIM_TOLERANCE = 1e-4  # on udot, wdot [m/s^2] and qdot [rad/s^2]: 0.1 m of drift in 45 s


@dataclass(frozen=True)
class Trim:
    """A straight and level equilibrium: controls and the engine speed that hold it."""

    alpha_rad: float
    elevator_rad: float
    throttle: float
    engine_rpm: float
    residual_accelerations: np.ndarray  # udot [m/s^2], wdot [m/s^2], qdot [rad/s^2]


def trim_level_flight(fdm: jsbsim.FGFDMExec, airspeed_mps: float, vehicle: Vehicle,
                      propeller: Propeller) -> Trim:
    """Trim the vehicle loaded in fdm in calm air at the position and altitude already in
    fdm's ic/ properties, starting from the vehicle's trim guess.

    The equilibrium is air-relative, so it holds in any steady uniform wind too (see
    `start_trimmed`). Leaves fdm's controls at the trim and the propeller model cleared.
    JSBSim's own engine is off while the trim evaluates (its propeller does not turn in
    run_ic()); the propeller model carries the propeller instead, as in the prediction model.
    """
    fdm[JSBSIM_ENGINE_ON] = 0
    fdm["ic/vt-fps"] = airspeed_mps / M_PER_FT
    fdm["ic/beta-rad"] = 0.0
    fdm["ic/phi-rad"] = 0.0
    fdm["ic/gamma-rad"] = 0.0
    fdm["ic/p-rad_sec"] = fdm["ic/q-rad_sec"] = fdm["ic/r-rad_sec"] = 0.0
    engine_rpm = 0.0

    def accelerations(x: np.ndarray) -> np.ndarray:
        nonlocal engine_rpm
        alpha_rad, elevator_rad, throttle = x
        fdm["ic/alpha-rad"] = alpha_rad
        fdm["ic/theta-rad"] = alpha_rad
        fdm["fcs/elevator-cmd-norm"] = elevator_rad / vehicle.surface_limit_rad
        fdm["fcs/throttle-cmd-norm"] = throttle
        fdm.run_ic()
        density = fdm["atmosphere/rho-slugs_ft3"] * KG_PER_M3_PER_SLUG_PER_FT3
        axial_speed_mps = fdm["velocities/u-aero-fps"] * M_PER_FT
        effective_throttle = fdm[EFFECTIVE_THROTTLE]
        engine_rpm = propeller.steady_rpm(effective_throttle, axial_speed_mps, density)
        apply_propeller_model(
            fdm,
            propeller.forces(engine_rpm, effective_throttle, axial_speed_mps, density, np.zeros(3)),
        )
        fdm.run_ic()
        return np.array(
            [
                fdm["accelerations/udot-ft_sec2"] * M_PER_FT,
                fdm["accelerations/wdot-ft_sec2"] * M_PER_FT,
                fdm["accelerations/qdot-rad_sec2"],
            ]
        )

    # Powell's hybrid method; JSBSim's alpha-dot from the previous evaluation leaves noise
    # of about 1e-7 in the accelerations, so the difference step is 1e-5.
    guess = vehicle.trim_guess
    solution = root(accelerations, x0=np.array([guess.alpha_rad, guess.elevator_rad,
                                                guess.throttle]),
                    method="hybr", options={"eps": 1e-10})
    residual = accelerations(solution.x)
    clear_propeller_model(fdm)
    fdm[JSBSIM_ENGINE_ON] = 1
    if not np.all(np.abs(residual) < TRIM_TOLERANCE):
        raise RuntimeError(
            f"no straight and level trim at {airspeed_mps:g} m/s: accelerations {residual}"
        )
    alpha_rad, elevator_rad, throttle = solution.x
    return Trim(float(alpha_rad), float(elevator_rad), float(throttle), engine_rpm, residual)


def start_trimmed(
    fdm: jsbsim.FGFDMExec,
    trim: Trim,
    airspeed_mps: float,
    heading_rad: float,
    wind_ned_mps: np.ndarray,
) -> None:
    """Initialise fdm in the trim, wings level on heading_rad, in a steady wind [m/s, NED].

    JSBSim's initial condition keeps ground-relative velocities when the wind changes, so the
    body velocities are set as the trim's air velocity plus the wind, in body axes.
    """
    north_mps, east_mps, _ = wind_ned_mps
    fdm["ic/vw-mag-fps"] = float(np.hypot(north_mps, east_mps)) / M_PER_FT
    fdm["ic/vw-dir-deg"] = float(np.degrees(np.arctan2(east_mps, north_mps)))
    fdm["ic/phi-rad"] = 0.0
    fdm["ic/theta-rad"] = trim.alpha_rad
    fdm["ic/psi-true-rad"] = heading_rad
    air_velocity_body = airspeed_mps * np.array(
        [np.cos(trim.alpha_rad), 0.0, np.sin(trim.alpha_rad)]
    )
    ground_velocity_body = (
        air_velocity_body + ned_to_body(0.0, trim.alpha_rad, heading_rad) @ wind_ned_mps
    )
    for axis, value_mps in zip("uvw", ground_velocity_body, strict=True):
        fdm[f"ic/{axis}-fps"] = float(value_mps) / M_PER_FT
    fdm.run_ic()
