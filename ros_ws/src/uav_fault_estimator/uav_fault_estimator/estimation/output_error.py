"""Output-error fit of the model's parameters over manoeuvres, as flight testers fit them.

Klein & Morelli, *Aircraft System Identification* (AIAA 2006), chapter 6: the equations of
motion are integrated over each manoeuvre from the measured inputs, and the parameters,
each manoeuvre's initial state and its wind are fitted to the measured outputs by
Gauss-Newton on the weighted output errors, the weights the inverse of the outputs' noise
variances re-estimated from the residuals after each fit (their relaxation technique).

The equations of motion are the vehicle's JSBSim model, as the prediction model evaluates
it (prediction.py, one model): flown open-loop from the logged surface deflections and
throttle, the engine off and the propeller turned at the logged engine speed through the
same tables and `propeller_model` reactions, the aircraft as the parameters say it differs
(model_parameters.changed). The outputs are what a small aircraft measures: attitude, body
rates, GNSS velocity, the pitot's true airspeed, and the vanes' angle of attack and
sideslip where the flight logged them (air-data biases applied as the sensors read them,
flown_aircraft.biased_air_data). Angle of attack and sideslip are states of the
integration, so the fit runs on a log without vanes; the angle-of-attack rate is the
integration's own.

The Gauss-Newton steps and the finite-difference Jacobian are scipy's least_squares (trust
region, bounds); each manoeuvre's unknowns touch its own outputs only, which the Jacobian's
sparsity says, so scipy perturbs every manoeuvre's initial state in one pass. The
Cramer-Rao bound is (J^T J)^-1 of the whitened Jacobian at the optimum, the prior's rows
included. No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix
from uav_aircraft.fdm import (
    FUEL_LOADED_LBS,
    JSBSIM_ENGINE_ON,
    KG_PER_LB,
    M_PER_FT,
    create_fdm,
    property_nodes,
)
from uav_aircraft.flown_aircraft import NOMINAL, FlownAircraft, biased_air_data
from uav_aircraft.propeller import Propeller
from uav_aircraft.vehicles import Vehicle
from uav_common.channels import AIR_DATA_CHANNELS, CONTROL_CHANNELS, STATE_CHANNELS

from uav_fault_estimator.estimation.model_calibration import SensorFlight
from uav_fault_estimator.estimation.model_parameters import ModelParameter, changed
from uav_fault_estimator.estimation.prediction import control_commands, turn_propeller

# The fit's JSBSim step [s]. The aircraft flown with its own parameters from a 3-2-1-1's
# measured start leaves roll-rate errors of 0.014 rad/s RMS at 120 Hz, 0.0095 at 240 Hz
# and 0.0077 at the simulator's 480 Hz (inputs logged at 120 Hz).
INTEGRATION_DT_S = 1.0 / 240.0
# The measured outputs: state channels, then the air data (AIR_DATA_CHANNELS order).
STATE_OUTPUTS = ("roll", "pitch", "yaw", "velocity_north", "velocity_east", "velocity_down",
                 "roll_rate", "pitch_rate", "yaw_rate")
OUTPUT_NAMES = STATE_OUTPUTS + AIR_DATA_CHANNELS
_YAW = OUTPUT_NAMES.index("yaw")
# The outputs' noise before the first fit [output unit]: attitude 0.5 deg, GNSS velocity
# 0.2 m/s, rates 0.01 rad/s, airspeed 0.5 m/s, vanes 0.5 deg; the relaxation replaces them.
FIRST_OUTPUT_STD = np.array([math.radians(0.5)] * 3 + [0.2] * 3 + [0.01] * 3
                            + [0.5, math.radians(0.5), math.radians(0.5)])
# Each manoeuvre's unknowns: its initial attitude [rad], NED ground velocity [m/s] and body
# rates [rad/s], and its constant wind, NED [m/s].
MANOEUVRE_UNKNOWNS = 12
RELAXATIONS = 3  # fits, each with the output noise the previous one left
# The finite-difference step relative to max(1, |value|): large against JSBSim's rounding,
# small against the outputs' curvature in each unknown.
DIFFERENCE_STEP = 1e-5
# A Gauss-Newton step that changes the cost or the unknowns by less than this share ends a
# fit: the parameters then move by far less than their Cramer-Rao deviations.
COST_TOLERANCE = 1e-6

_STATE = {name: index for index, name in enumerate(STATE_CHANNELS)}
_CONTROL = {name: index for index, name in enumerate(CONTROL_CHANNELS)}
_OUTPUT_PROPERTIES = ("attitude/phi-rad", "attitude/theta-rad", "attitude/psi-rad",
                      "velocities/v-north-fps", "velocities/v-east-fps", "velocities/v-down-fps",
                      "velocities/p-rad_sec", "velocities/q-rad_sec", "velocities/r-rad_sec",
                      "velocities/vt-fps", "aero/alpha-rad", "aero/beta-rad")
_FEET_OUTPUTS = np.array([name.endswith("-fps") for name in _OUTPUT_PROPERTIES])
# The unknowns' properties; the wind is the atmosphere's, set after run_ic() (which resets
# it) and before the first step.
_INITIAL_PROPERTIES = ("ic/phi-rad", "ic/theta-rad", "ic/psi-true-rad",
                       "ic/vn-fps", "ic/ve-fps", "ic/vd-fps",
                       "ic/p-rad_sec", "ic/q-rad_sec", "ic/r-rad_sec",
                       "atmosphere/wind-north-fps", "atmosphere/wind-east-fps",
                       "atmosphere/wind-down-fps")
_INITIAL_IN_FEET = np.array([name.endswith("-fps") for name in _INITIAL_PROPERTIES])


@dataclass(frozen=True)
class Manoeuvre:
    """Samples start .. stop - 1 of a recorded flight (SensorFlight, at its sensor rate),
    integrated as one: a manoeuvre and the flight around it that its response lasts."""

    flight: SensorFlight
    start: int
    stop: int

    def measured(self) -> np.ndarray:
        """The measured outputs (K, 12), OUTPUT_NAMES order; NaN where not measured."""
        states = self.flight.states[self.start:self.stop]
        return np.hstack([states[:, [_STATE[name] for name in STATE_OUTPUTS]],
                          self.flight.air_data[self.start:self.stop]])

    def first_guess(self) -> np.ndarray:
        """Its unknowns (MANOEUVRE_UNKNOWNS,) as measured at its first sample, the wind the
        flight's filtered one."""
        first = self.measured()[0]
        return np.concatenate([first[:9], self.flight.winds_ned_mps[self.start]])


@dataclass(frozen=True)
class OutputErrorFit:
    """The fit: per parameter its value and Cramer-Rao deviation [its unit]; per manoeuvre
    its unknowns (MANOEUVRE_UNKNOWNS,); the outputs' noise deviations (12,) of the last
    relaxation [output unit]; the weighted squared error per output sample (the
    likelihood's reduced chi-square, 1 at a fit that leaves only the noise), and the
    integrations it took."""

    values: dict[str, float]
    deviations: dict[str, float]
    manoeuvre_unknowns: np.ndarray
    output_std: np.ndarray
    reduced_chi_square: float
    integrations: int


class ManoeuvreFlyer:
    """Flies manoeuvres of one vehicle open-loop in its JSBSim model (module docstring)."""

    def __init__(self, vehicle: Vehicle, base: FlownAircraft = NOMINAL,
                 dt_s: float = INTEGRATION_DT_S) -> None:
        self.vehicle = vehicle
        self.base = base
        self.dt_s = dt_s
        self.propeller = Propeller.from_vehicle(vehicle)
        self.commands = control_commands(vehicle)

    def fly(self, parameters: Sequence[ModelParameter], values: np.ndarray,
            manoeuvre: Manoeuvre, unknowns: np.ndarray) -> np.ndarray:
        """The outputs (K, 12) the model predicts at the manoeuvre's samples, with the
        parameters at values [their units] and its unknowns (Manoeuvre.first_guess's)."""
        aircraft = changed(self.base, dict(zip((p.name for p in parameters), values,
                                               strict=True)))
        fdm = create_fdm(self.vehicle, self.dt_s, aircraft)
        fdm[JSBSIM_ENGINE_ON] = 0
        flight, first = manoeuvre.flight, manoeuvre.start
        state = flight.states[first]
        fdm["ic/lat-geod-rad"] = float(state[_STATE["latitude"]])
        fdm["ic/long-gc-rad"] = float(state[_STATE["longitude"]])
        fdm["ic/h-sl-ft"] = float(state[_STATE["altitude"]]) / M_PER_FT
        fdm[FUEL_LOADED_LBS] = float(state[_STATE["fuel_mass"]]) / KG_PER_LB
        initial = np.where(_INITIAL_IN_FEET, unknowns / M_PER_FT, unknowns)
        for name, value in zip(_INITIAL_PROPERTIES[:9], initial[:9], strict=True):
            fdm[name] = float(value)
        # The wind in the initial condition too: else the first step's angle of attack jumps
        # and JSBSim's alpha-dot kicks the pitch.
        north_fps, east_fps, down_fps = initial[9:]
        fdm["ic/vw-mag-fps"] = float(math.hypot(north_fps, east_fps))
        fdm["ic/vw-dir-deg"] = math.degrees(math.atan2(east_fps, north_fps))
        fdm["ic/vw-down-fps"] = float(down_fps)
        times_s = flight.times_s[first:manoeuvre.stop]
        steps = np.arange(0.0, times_s[-1] - times_s[0] + 0.5 * self.dt_s, self.dt_s)
        # A logged control is what acted over the step before its sample (the FCS's
        # output of the last step): each step gets the control at its end.
        inputs = self._inputs(manoeuvre, times_s[0] + steps + self.dt_s)
        record_at = np.searchsorted(times_s[0] + steps, times_s - 0.5 * self.dt_s)
        set_commands = [node.set_double_value
                        for node in property_nodes(fdm, [c for c, _ in self.commands.values()])]
        read_outputs = [node.get_double_value for node in property_nodes(fdm, _OUTPUT_PROPERTIES)]
        read_rates = [node.get_double_value for node in property_nodes(
            fdm, [f"velocities/{axis}-rad_sec" for axis in "pqr"])]
        for set_value, value in zip(set_commands, inputs[0, :-1], strict=True):
            set_value(float(value))
        fdm.run_ic()
        for name, value in zip(_INITIAL_PROPERTIES[9:], initial[9:], strict=True):
            fdm[name] = float(value)
        outputs = np.empty((times_s.size, len(_OUTPUT_PROPERTIES)))
        recorded = 0
        for step, row in enumerate(inputs):
            for set_value, value in zip(set_commands, row[:-1], strict=True):
                set_value(float(value))
            turn_propeller(fdm, self.propeller, float(row[-1]),
                           np.array([read() for read in read_rates]))
            while recorded < times_s.size and record_at[recorded] == step:
                outputs[recorded] = [read() for read in read_outputs]
                recorded += 1
            fdm.run()
        outputs[:, _FEET_OUTPUTS] *= M_PER_FT
        outputs[:, 9:] = biased_air_data(outputs[:, 9:].T, aircraft.sensor_bias).T
        return outputs

    def _inputs(self, manoeuvre: Manoeuvre, times_s: np.ndarray) -> np.ndarray:
        """Per integration step the JSBSim commands (control_commands order) and the engine speed
        [rpm], linear between the logged samples."""
        flight, span = manoeuvre.flight, slice(manoeuvre.start, manoeuvre.stop)
        logged_s = flight.times_s[span]
        logged = np.column_stack(
            [flight.controls[span, [_CONTROL[channel] for channel in self.commands]],
             flight.states[span, _STATE["engine_speed"]]])
        units = np.array([unit for _, unit in self.commands.values()] + [1.0])
        columns = np.column_stack([np.interp(times_s, logged_s, column) for column in logged.T])
        columns /= units
        flap = list(self.commands).index("flap")
        columns[:, flap] = np.maximum(columns[:, flap], 0.0)  # JSBSim's flap takes 0..1
        return columns


def output_errors(measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """measured - predicted (K, 12), the yaw's wrapped to [-pi, pi), 0 where not measured."""
    errors = measured - predicted
    errors[:, _YAW] = (errors[:, _YAW] + math.pi) % (2.0 * math.pi) - math.pi
    return np.nan_to_num(errors, nan=0.0)


def fit_output_error(flyer: ManoeuvreFlyer, manoeuvres: Sequence[Manoeuvre],
                     parameters: Sequence[ModelParameter],
                     relaxations: int = RELAXATIONS) -> OutputErrorFit:
    """Fit the parameters (each about its prior 0 with its prior_std, within its bounds),
    every manoeuvre's unknowns and the outputs' noise to the manoeuvres (module
    docstring): `relaxations` fits each followed by a new noise estimate, then the last.
    RuntimeError where an integration leaves the flight envelope (non-finite outputs)."""
    n = len(parameters)
    measured = [m.measured() for m in manoeuvres]
    guess = np.concatenate([np.zeros(n), *(m.first_guess() for m in manoeuvres)])
    lower = np.concatenate([[p.bounds[0] for p in parameters],
                            np.full(MANOEUVRE_UNKNOWNS * len(manoeuvres), -np.inf)])
    upper = np.concatenate([[p.bounds[1] for p in parameters],
                            np.full(MANOEUVRE_UNKNOWNS * len(manoeuvres), np.inf)])
    prior_std = np.array([p.prior_std for p in parameters])
    output_std = FIRST_OUTPUT_STD.copy()
    integrations = 0

    def weighted_errors(x: np.ndarray) -> np.ndarray:
        nonlocal integrations
        blocks = [(x[:n]) / prior_std]
        for k, (manoeuvre, z) in enumerate(zip(manoeuvres, measured, strict=True)):
            unknowns = x[n + MANOEUVRE_UNKNOWNS * k:n + MANOEUVRE_UNKNOWNS * (k + 1)]
            predicted = flyer.fly(parameters, x[:n], manoeuvre, unknowns)
            integrations += 1
            if not np.all(np.isfinite(predicted)):
                raise RuntimeError(f"the model left the envelope flying samples "
                                   f"{manoeuvre.start}-{manoeuvre.stop} of "
                                   f"{manoeuvre.flight.name}")
            blocks.append((output_errors(z, predicted) / output_std).ravel())
        return np.concatenate(blocks)

    sparsity = _jacobian_sparsity(n, [z.shape[0] for z in measured])

    def solve(start: np.ndarray):
        return least_squares(weighted_errors, start, jac_sparsity=sparsity,
                             bounds=(lower, upper), diff_step=DIFFERENCE_STEP, x_scale="jac",
                             method="trf", ftol=COST_TOLERANCE, xtol=COST_TOLERANCE)

    counted = np.vstack([np.isfinite(z) for z in measured])
    x = guess
    for _ in range(relaxations):
        result = solve(x)
        x = result.x
        # the output errors at the optimum: its weighted errors (after the prior's rows)
        # times the weights' deviations
        errors = result.fun[n:].reshape(-1, len(OUTPUT_NAMES)) * output_std
        mean_square = (errors**2).sum(axis=0) / np.maximum(counted.sum(axis=0), 1)
        output_std = np.where(counted.any(axis=0), np.sqrt(mean_square), output_std)
    result = solve(x)
    jacobian = result.jac.toarray() if hasattr(result.jac, "toarray") else result.jac
    covariance = np.linalg.pinv(jacobian.T @ jacobian)
    samples = sum(int(np.isfinite(z).sum()) for z in measured)
    return OutputErrorFit(
        values={p.name: float(v) for p, v in zip(parameters, result.x[:n], strict=True)},
        deviations={p.name: float(math.sqrt(covariance[i, i]))
                    for i, p in enumerate(parameters)},
        manoeuvre_unknowns=result.x[n:].reshape(len(manoeuvres), MANOEUVRE_UNKNOWNS),
        output_std=output_std,
        reduced_chi_square=float(2.0 * result.cost / max(samples, 1)),
        integrations=integrations,
    )


def _jacobian_sparsity(parameters: int, samples: Sequence[int]) -> lil_matrix:
    """Which weighted errors each unknown moves: the parameters all, a manoeuvre's unknowns
    its own outputs; the prior's rows their own parameter."""
    outputs = len(OUTPUT_NAMES)
    rows = parameters + outputs * sum(samples)
    columns = parameters + MANOEUVRE_UNKNOWNS * len(samples)
    sparsity = lil_matrix((rows, columns), dtype=int)
    for i in range(parameters):
        sparsity[i, i] = 1
    row = parameters
    for k, count in enumerate(samples):
        block = slice(row, row + outputs * count)
        sparsity[block, :parameters] = 1
        first = parameters + MANOEUVRE_UNKNOWNS * k
        sparsity[block, first:first + MANOEUVRE_UNKNOWNS] = 1
        row += outputs * count
    return sparsity
