"""What a calibration's flights could tell, and what manoeuvre would tell the rest.

A parameter is informed by a flight when that flight alone (with the prior) brings its
posterior deviation below INFORMED_SHARE of its prior deviation. A pair the flights could not
separate is told apart by exciting the axes its parameters act on: each parameter belongs
to the axis whose motion shows it (AXIS_OF: roll, pitch, yaw, or throttle for what trades
thrust against drag and mass), and MANOEUVRE_FOR_AXIS says what flight testers fly on that
axis (a scenario's `manoeuvres:`, uav_sim.manoeuvres; ArduPlane's SID_AXIS, PX4's
FW_AT_SYSID_*). Bands are for a small fixed-wing's modes: roll subsidence and short
period about 0.5-2 Hz, Dutch roll 0.3-1.5 Hz, phugoid about 0.05 Hz.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

INFORMED_SHARE = 0.5  # a flight alone halves the prior deviation: it informs the parameter
AXES = ("roll", "pitch", "yaw", "throttle")
# Each parameter's axis: by name for the aircraft's, by the coefficient's prefix otherwise
# (JSBSim's names: CL lift, CD drag, CY side force, Cl roll, Cm pitch, Cn yaw moment)
AXIS_OF = {"mass_scale": "throttle", "thrust_scale": "throttle", "airspeed_scale": "throttle",
           "inertia_x_scale": "roll", "inertia_y_scale": "pitch", "inertia_z_scale": "yaw",
           "cg_x_cm": "pitch", "cg_y_cm": "roll", "cg_z_cm": "pitch",
           "angle_of_attack_deg": "pitch", "sideslip_deg": "yaw"}
_PREFIX_AXIS = (("CL", "pitch"), ("CD", "throttle"), ("CY", "yaw"), ("Cl", "roll"),
                ("Cm", "pitch"), ("Cn", "yaw"))
MANOEUVRE_FOR_AXIS = {
    "roll": "roll, surface: a 3211 of 0.3-0.5 s steps and a multisine 0.1-1.5 Hz",
    "pitch": "pitch, surface: a 3211 of 0.3-0.5 s steps and a multisine 0.1-1.5 Hz; a climb",
    "yaw": "yaw: steady sideslips (attitude doublet of 10 s steps) and a rudder multisine "
           "0.1-1.5 Hz",
    "throttle": "throttle: a doublet of 5 s steps and an airspeed step of 4 m/s",
}


def parameter_axis(name: str) -> str:
    """The axis whose motion shows the parameter (AXES)."""
    if name in AXIS_OF:
        return AXIS_OF[name]
    for prefix, axis in _PREFIX_AXIS:
        if name.startswith(prefix):
            return axis
    raise ValueError(f"no axis known for parameter {name}")


def informing_flights(flight_posterior_std: np.ndarray, prior_std: np.ndarray,
                      flight_names: Sequence[str]) -> list[list[str]]:
    """Per parameter, the names of the flights that inform it (flight_posterior_std: the
    deviation each flight alone gives, (flights, n); prior_std (n,), the same unit)."""
    informed = flight_posterior_std < INFORMED_SHARE * prior_std[None, :]
    return [[flight_names[f] for f in np.flatnonzero(informed[:, j])]
            for j in range(len(prior_std))]


def separating_manoeuvres(first: str, second: str) -> list[str]:
    """What would tell the two parameters apart: the manoeuvre of each one's axis (one when
    they share it)."""
    axes = dict.fromkeys((parameter_axis(first), parameter_axis(second)))
    return [MANOEUVRE_FOR_AXIS[axis] for axis in axes]
