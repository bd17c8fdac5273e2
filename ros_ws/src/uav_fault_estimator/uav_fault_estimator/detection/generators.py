"""The self-tuning residual generators (Blanke & Hansen, eq. 2-8, and the ones added here):
each a model linear in its parameters, y[k] = phi[k]ᵀ theta, identified in flight by RLS
(rls.py). A calibration names the generators it was made for; the detector runs those.

The paper's three, and the lateral pair with a rudder the autopilot commands on its own
(not a copy of the aileron) as the other lateral input:

    roll         p[k] = a_pa da[k] + b_pa                           (eq. 2)
    pitch        q[k] = a_qe de[k] + b_qe                           (eq. 3)
    yaw          r[k] = a_ra da[k] + b_ra r[k-1] + c_ra             (eq. 4)
    roll_rudder  p[k] = a_pa da[k] + a_pr dr[k] + b_pa
    yaw_rudder   r[k] = a_ra da[k] + b_ra r[k-1] + a_rr dr[k] + c_ra

These read the surface commands: on a real aircraft whose failure shows in its outputs (a
servo pinned by the failure), a generator fed that output sees an aircraft consistent with
it. The tracking generators read the autopilot's intent instead, its setpoints, against the
aircraft's response; the propulsion channel the throttle it needs:

    roll_tracking   p[k] = a (phi_c[k] - phi[k]) + b            the roll loop's response
    pitch_tracking  q[k] = a (theta_c[k] - theta[k]) + b        the pitch loop's response
    climb_tracking  h'[k] = a h'_c[k] + b                       the climb the autopilot gets
    lateral_force   f_y[k] = c                                  the sideslip's side force
    longitudinal_force  f_x[k] = c                              thrust less drag, per mass
    propulsion      throttle[k] = a sin(gamma[k]) + b (1 / cos(phi[k])^2 - 1) + c

p, q, r body rates [rad/s]; da aileron, de elevator, dr rudder [rad]; phi, theta roll and
pitch and phi_c, theta_c their setpoints [rad]; h' the climb rate (the ground velocity's,
up) and h'_c the autopilot's commanded one [m/s]; throttle 0..1; gamma the flight-path angle
from the ground velocity. An engine that stops shows in climb_tracking: the aircraft sinks
whatever climb its autopilot commands. lateral_force is the body-y specific force f_y
[m/s^2] (uav_aircraft.frames), from the ground velocity's change since the sample before: an
autopilot that coordinates its turns flies with f_y near a constant (the sensors' bias),
and a rudder stuck off centre holds the aircraft in a sideslip whose side force shows
within a second, whatever the roll loop does to hide it. longitudinal_force is its body-x
twin, thrust less drag per unit mass: an autopilot holding its speed holds it near a
constant, and an engine that stops drops it by the cruise thrust over the mass at once,
before the speed or the height shows it. The propulsion channel is the
throttle the autopilot needs to hold its speed against the climb it flies and its turns'
load factor (n^2 - 1, the induced drag's share): a loss of thrust raises it (c, and the
residual). Where a failure cuts the throttle output itself (ALFA's engine failures), it
reads the injection.
No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from uav_aircraft.frames import specific_force_body_mps2
from uav_common.channels import CONTROL_CHANNELS, SETPOINT_FIELDS, STATE_CHANNELS

_P, _Q, _R = (STATE_CHANNELS.index(name) for name in ("roll_rate", "pitch_rate", "yaw_rate"))
_ROLL, _PITCH, _YAW = (STATE_CHANNELS.index(name) for name in ("roll", "pitch", "yaw"))
_VN, _VE, _VD = (STATE_CHANNELS.index(name)
                  for name in ("velocity_north", "velocity_east", "velocity_down"))
_AILERON, _ELEVATOR, _RUDDER, _THROTTLE = (CONTROL_CHANNELS.index(name)
                                           for name in ("aileron", "elevator", "rudder",
                                                        "throttle"))
MIN_SPEED_MPS = 1.0  # below it the flight-path angle is not defined: the aircraft stands


# The autopilot's setpoints a generator may read, in this order (NaN where unknown): the
# fields of AutopilotSetpoints.
SETPOINTS = SETPOINT_FIELDS
_ROLL_SETPOINT, _PITCH_SETPOINT, _DOWN_SETPOINT = range(len(SETPOINTS))
NO_SETPOINTS = np.full(len(SETPOINTS), math.nan)


class GridSample(NamedTuple):
    """One sample on the detector's grid: its time [s], state (14,) and controls (7,) in
    uav_common.channels order, setpoints (SETPOINTS order: commanded roll and pitch [rad],
    commanded vertical velocity, down [m/s]; NaN unknown)."""

    time_s: float
    state: np.ndarray
    controls: np.ndarray
    setpoints: np.ndarray


# (phi, y) of a generator from this sample and the one before (None: not known)
Regression = tuple[np.ndarray, float]


@dataclass(frozen=True)
class Generator:
    """A residual generator: its name (the detector's channel), its parameters' names, and
    regression(now, before) -> (phi, y); before is None after a start or a gap, and a
    generator that needs it (needs_previous) cannot run then."""

    name: str
    parameters: tuple[str, ...]
    needs_previous: bool
    regression: Callable[[GridSample, GridSample | None], Regression]


def _roll(now: GridSample, before: GridSample | None) -> Regression:
    return np.array([now.controls[_AILERON], 1.0]), now.state[_P]  # eq. 2, 5


def _pitch(now: GridSample, before: GridSample | None) -> Regression:
    return np.array([now.controls[_ELEVATOR], 1.0]), now.state[_Q]  # eq. 3, 6


def _yaw(now: GridSample, before: GridSample) -> Regression:
    return np.array([now.controls[_AILERON], before.state[_R], 1.0]), now.state[_R]  # eq. 4, 7


def _roll_rudder(now: GridSample, before: GridSample | None) -> Regression:
    controls = now.controls
    return np.array([controls[_AILERON], controls[_RUDDER], 1.0]), now.state[_P]


def _yaw_rudder(now: GridSample, before: GridSample) -> Regression:
    controls = now.controls
    return (np.array([controls[_AILERON], before.state[_R], controls[_RUDDER], 1.0]),
            now.state[_R])


def _roll_tracking(now: GridSample, before: GridSample | None) -> Regression:
    error_rad = _angle_rad(now.setpoints[_ROLL_SETPOINT] - now.state[_ROLL])
    return np.array([error_rad, 1.0]), now.state[_P]


def _pitch_tracking(now: GridSample, before: GridSample | None) -> Regression:
    error_rad = _angle_rad(now.setpoints[_PITCH_SETPOINT] - now.state[_PITCH])
    return np.array([error_rad, 1.0]), now.state[_Q]


def _climb_tracking(now: GridSample, before: GridSample | None) -> Regression:
    return np.array([-now.setpoints[_DOWN_SETPOINT], 1.0]), -now.state[_VD]


def _specific_force_mps2(now: GridSample, before: GridSample) -> np.ndarray:
    """The body-axes specific force [m/s^2] from the ground velocity's change since before."""
    velocity = [_VN, _VE, _VD]
    elapsed_s = now.time_s - before.time_s  # > 0: the grid's samples come in time order
    acceleration_ned_mps2 = (now.state[velocity] - before.state[velocity]) / elapsed_s
    return specific_force_body_mps2(acceleration_ned_mps2, *now.state[[_ROLL, _PITCH, _YAW]])


def _lateral_force(now: GridSample, before: GridSample) -> Regression:
    return np.array([1.0]), _specific_force_mps2(now, before)[1]


def _longitudinal_force(now: GridSample, before: GridSample) -> Regression:
    return np.array([1.0]), _specific_force_mps2(now, before)[0]


def _propulsion(now: GridSample, before: GridSample | None) -> Regression:
    velocity_mps = now.state[[_VN, _VE, _VD]]
    climb = -velocity_mps[2] / max(float(np.linalg.norm(velocity_mps)), MIN_SPEED_MPS)
    load = 1.0 / math.cos(now.state[_ROLL]) ** 2 - 1.0
    return np.array([climb, load, 1.0]), now.controls[_THROTTLE]


def _angle_rad(angle_rad: float) -> float:
    """An angle difference [rad] into [-pi, pi)."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


GENERATORS: Mapping[str, Generator] = {generator.name: generator for generator in (
    Generator("roll", ("a_pa", "b_pa"), False, _roll),
    Generator("pitch", ("a_qe", "b_qe"), False, _pitch),
    Generator("yaw", ("a_ra", "b_ra", "c_ra"), True, _yaw),
    Generator("roll_rudder", ("a_pa", "a_pr", "b_pa"), False, _roll_rudder),
    Generator("yaw_rudder", ("a_ra", "b_ra", "a_rr", "c_ra"), True, _yaw_rudder),
    Generator("roll_tracking", ("a_rt", "b_rt"), False, _roll_tracking),
    Generator("pitch_tracking", ("a_pt", "b_pt"), False, _pitch_tracking),
    Generator("climb_tracking", ("a_ct", "b_ct"), False, _climb_tracking),
    Generator("lateral_force", ("c_fy",), True, _lateral_force),
    Generator("longitudinal_force", ("c_fx",), True, _longitudinal_force),
    Generator("propulsion", ("a_tg", "b_tn", "c_t"), False, _propulsion),
)}
# The failure kinds (ALFA's words) and the generators that read what each failed part acts
# on: the surface's own axis (open loop, and its loop's tracking; the rudder's sideslip, in
# the side force), the engine's energy (the throttle it needs, the climb it can no longer
# hold, the thrust it no longer gives). An alarm names the kind of its strongest channel.
FAILURE_GENERATORS: Mapping[str, tuple[str, ...]] = {
    "aileron": ("roll", "roll_rudder", "roll_tracking"),
    "elevator": ("pitch", "pitch_tracking"),
    "rudder": ("yaw", "yaw_rudder", "lateral_force"),
    "engine": ("propulsion", "climb_tracking", "longitudinal_force")}
KIND_OF_GENERATOR = {generator: kind for kind, generators in FAILURE_GENERATORS.items()
                     for generator in generators}
# The paper's three.
SURFACE_GENERATORS = ("roll", "pitch", "yaw")
# What a vehicle's shipped calibration uses: the autopilot's intent against the aircraft's
# response and the aircraft's own motion, never a surface output that a failure pins (the
# paper's three read those: their fast test found none of the aileron and elevator failures
# of the dev flights within 5 s; these found 20, 18 and 19 of 20 on the Carbon-Z,
# docs/detector.md).
SHIPPED_GENERATORS = ("roll_tracking", "pitch_tracking", "lateral_force", "longitudinal_force")


def generator_names(text: str) -> tuple[str, ...]:
    """Generator names as a command line gives them: separated by commas."""
    return tuple(name.strip() for name in text.split(",") if name.strip())


def checked_generators(names: tuple[str, ...]) -> tuple[str, ...]:
    """names when each is a generator's and none repeats; ValueError otherwise."""
    unknown = [name for name in names if name not in GENERATORS]
    if unknown or len(set(names)) != len(names) or not names:
        raise ValueError(f"generators {', '.join(names) or 'none'}: expected some of "
                         f"{', '.join(GENERATORS)}, each once")
    return names


def regressions(names: tuple[str, ...], now: GridSample,
                before: GridSample | None) -> dict[str, Regression] | None:
    """(phi, y) of each named generator; None when one cannot run on this sample (it needs
    the sample before and there is none, or a value it takes is not finite)."""
    found = {}
    for name in names:
        generator = GENERATORS[name]
        if generator.needs_previous and before is None:
            return None
        phi, y = generator.regression(now, before)
        if not (np.all(np.isfinite(phi)) and math.isfinite(y)):
            return None
        found[name] = (phi, float(y))
    return found
