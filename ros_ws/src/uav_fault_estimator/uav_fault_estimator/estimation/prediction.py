"""The prediction model phi: a vehicle's accelerations at a measured state.

Embedded-estimation paper, eq. 6: a_hat = phi(p, v, u, zeta, w_hat | f). The model is the
JSBSim vehicle the simulator flies (uav_aircraft's aircraft folder, one source of truth,
docs/design.md), evaluated with `run_ic()`, which computes the accelerations of a given state
without integrating. Per evaluation:

- Wind: the filtered wind w_hat enters through the air-relative velocity. The predictor
  flies in still air with body velocity C_bn (v_ned - w_hat), because run_ic() resets the
  wind to the initial-condition wind; turbulence stays off.
- Propeller: JSBSim's engine is switched off (`propulsion/jsbsim-engine-on` = 0): its
  propeller speed is a state run_ic() never advances. The thrust and hub moment at the
  measured engine speed come from the same propeller tables (uav_aircraft.propeller) and act
  through the aircraft's `propeller_model` reactions. An aircraft whose engine speed is not
  measured (steady_engine_speed) turns it at the speed where the propeller absorbs the
  engine's power at the throttle, as the trim does: the engine's lag is left out.
- Mass: the fuel on board is the measured fuel mass.
- Aircraft: the vehicle's XML as shipped, or as a model calibration (model_calibration.py)
  says the flown aircraft differs from it (a FlownAircraft: mass, coefficient and thrust scales).
- run_ic() runs twice: the first gives air density and effective throttle for the
  propeller, and the accelerations from which JSBSim forms alpha-dot in the second.

Output: (dv_N/dt, dv_E/dt, dv_D/dt) [m/s^2], the rate of change of the NED velocity, and
(dp/dt, dq/dt, dr/dt) [rad/s^2] about body axes. JSBSim gives the body-axis derivative of
the body velocity, so dv_ned/dt = C_bn^T (d(u, v, w)/dt + omega x (u, v, w)). In a steady
wind the air-relative and ground velocities change alike; the filtered wind's own rate
(time constant 10 s) is left out.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import jsbsim
import numpy as np
from uav_aircraft.fdm import (
    BODY_ACCELERATIONS,
    EFFECTIVE_THROTTLE,
    FUEL_LOADED_LBS,
    JSBSIM_ENGINE_ON,
    KG_PER_LB,
    KG_PER_M3_PER_SLUG_PER_FT3,
    M_PER_FT,
    apply_propeller_model,
    create_fdm,
    property_nodes,
    set_faults,
)
from uav_aircraft.flown_aircraft import NOMINAL, FlownAircraft
from uav_aircraft.frames import ned_to_body
from uav_aircraft.propeller import Propeller
from uav_aircraft.vehicles import Vehicle, load_vehicle
from uav_common.channels import CONTROL_CHANNELS, MODEL_FAULT_NAMES, STATE_CHANNELS

from uav_fault_estimator.estimation.residual_sampling import ResidualSampler
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.estimation.residuals import PredictorFactory, ResidualGenerator

_STATE = {name: index for index, name in enumerate(STATE_CHANNELS)}
_CONTROL = {name: index for index, name in enumerate(CONTROL_CHANNELS)}
_VELOCITY_NED = [_STATE[name] for name in ("velocity_north", "velocity_east", "velocity_down")]
_BODY_RATES = [_STATE[name] for name in ("roll_rate", "pitch_rate", "yaw_rate")]


def control_commands(vehicle: Vehicle) -> dict[str, tuple[str, float]]:
    """Control channel -> (JSBSim command, measured value per unit command). Surfaces follow
    their commands without lag in the vehicle's FCS, so the measured position gives the
    command."""
    return {
        "flap": ("fcs/flap-cmd-norm", vehicle.flap_limit_rad),
        "elevator": ("fcs/elevator-cmd-norm", vehicle.surface_limit_rad),
        "aileron": ("fcs/aileron-cmd-norm", vehicle.surface_limit_rad),
        "rudder": ("fcs/rudder-cmd-norm", vehicle.surface_limit_rad),
        "throttle": ("fcs/throttle-cmd-norm", 1.0),
        "mixture": ("fcs/mixture-cmd-norm", 1.0),
        "ignition": ("fcs/ignition-cmd", 1.0),
    }

_POSITION_AND_ATTITUDE = {
    "latitude": ("ic/lat-geod-rad", 1.0),
    "longitude": ("ic/long-gc-rad", 1.0),
    "altitude": ("ic/h-sl-ft", M_PER_FT),
    "roll": ("ic/phi-rad", 1.0),
    "pitch": ("ic/theta-rad", 1.0),
    "yaw": ("ic/psi-true-rad", 1.0),
}


def _setters(fdm: jsbsim.FGFDMExec, names: Sequence[str]) -> list[Callable[[float], None]]:
    """A setter of each named property, in the names' order."""
    return [node.set_double_value for node in property_nodes(fdm, names)]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b of two 3-vectors: np.cross's products and differences in its order (the same
    bits) without its handling of general shapes (about 10 us a call)."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


class AircraftPredictor:
    """phi(x | f) for one fixed fault vector f: a JSBSim copy of the vehicle of its own, the
    shipped one or as `aircraft` says the flown one differs."""

    def __init__(self, faults_pct: Mapping[str, float], vehicle: Vehicle, propeller: Propeller,
                 aircraft: FlownAircraft = NOMINAL, steady_engine_speed: bool = False) -> None:
        """steady_engine_speed: ignore the state's engine speed and turn the propeller at its
        steady speed for the throttle (module docstring)."""
        unknown = sorted(set(faults_pct) - set(MODEL_FAULT_NAMES))
        if unknown:
            raise ValueError(f"unknown fault names {unknown}; known: "
                             f"{', '.join(MODEL_FAULT_NAMES)}")
        self.faults_pct = dict(faults_pct)
        self.propeller = propeller
        self.steady_engine_speed = steady_engine_speed
        self.commands = control_commands(vehicle)
        self.fdm: jsbsim.FGFDMExec = create_fdm(vehicle, aircraft=aircraft)
        self.fdm[JSBSIM_ENGINE_ON] = 0
        set_faults(self.fdm, self.faults_pct)
        # the initial-condition and command properties each call writes (nodes found once)
        self.set_position_and_attitude = _setters(
            self.fdm, [name for name, _ in _POSITION_AND_ATTITUDE.values()])
        self.set_commands = _setters(self.fdm, [name for name, _ in self.commands.values()])
        self.set_air_velocity = _setters(self.fdm, [f"ic/{axis}-fps" for axis in "uvw"])
        self.set_body_rates = _setters(self.fdm, [f"ic/{axis}-rad_sec" for axis in "pqr"])
        (self.set_fuel,) = _setters(self.fdm, [FUEL_LOADED_LBS])

    def __call__(
        self, state: np.ndarray, controls: np.ndarray, wind_ned_mps: np.ndarray
    ) -> np.ndarray:
        """Accelerations (6,) at state (14,), controls (7,) and filtered wind [m/s] (3,).

        Orders and units are those of uav_common.channels; the output is described in the
        module docstring. Every input must be finite.
        """
        fdm = self.fdm
        to_body = ned_to_body(*state[[_STATE["roll"], _STATE["pitch"], _STATE["yaw"]]])
        air_velocity_body_mps = to_body @ (state[_VELOCITY_NED] - wind_ned_mps)
        body_rates_radps = state[_BODY_RATES]
        for set_value, (channel, (_, unit)) in zip(
                self.set_position_and_attitude, _POSITION_AND_ATTITUDE.items(), strict=True):
            set_value(float(state[_STATE[channel]]) / unit)
        for set_value, value_mps in zip(self.set_air_velocity, air_velocity_body_mps,
                                        strict=True):
            set_value(float(value_mps) / M_PER_FT)
        for set_value, value_radps in zip(self.set_body_rates, body_rates_radps, strict=True):
            set_value(float(value_radps))
        for set_value, (channel, (_, unit)) in zip(self.set_commands, self.commands.items(),
                                                   strict=True):
            command = float(controls[_CONTROL[channel]]) / unit
            # The flap's FCS takes commands 0..1 only (below 0 JSBSim's aerosurface_scale
            # gives NaN); sensor noise makes a retracted flap read a little below 0.
            set_value(max(command, 0.0) if channel == "flap" else command)
        self.set_fuel(float(state[_STATE["fuel_mass"]]) / KG_PER_LB)
        fdm.run_ic()
        turn_propeller(fdm, self.propeller,
                       None if self.steady_engine_speed else float(state[_STATE["engine_speed"]]),
                       body_rates_radps)
        fdm.run_ic()
        derivatives = np.array([fdm[name] for name in BODY_ACCELERATIONS])
        velocity_rate_body = derivatives[:3] * M_PER_FT + _cross(
            body_rates_radps, air_velocity_body_mps
        )
        return np.concatenate([to_body.T @ velocity_rate_body, derivatives[3:]])


def turn_propeller(fdm: jsbsim.FGFDMExec, propeller: Propeller, engine_rpm: float | None,
                   body_rates_radps: np.ndarray) -> None:
    """Put the propeller's thrust and hub moment on the aircraft's `propeller_model`
    reactions (its JSBSim engine off): at engine_rpm [rpm], or where None at the speed where
    it absorbs the engine's power at the throttle; the air density, effective throttle and
    axial speed JSBSim's last evaluation left; body_rates_radps (3,) for the gyroscopic
    moment."""
    density_kg_m3 = fdm["atmosphere/rho-slugs_ft3"] * KG_PER_M3_PER_SLUG_PER_FT3
    effective_throttle = fdm[EFFECTIVE_THROTTLE]
    axial_speed_mps = fdm["velocities/u-aero-fps"] * M_PER_FT
    if engine_rpm is None:
        engine_rpm = propeller.steady_rpm(effective_throttle, axial_speed_mps, density_kg_m3)
    apply_propeller_model(fdm, propeller.forces(
        engine_rpm, effective_throttle, axial_speed_mps, density_kg_m3, body_rates_radps))


def aircraft_predictor_factory(vehicle: Vehicle, aircraft: FlownAircraft = NOMINAL,
                               steady_engine_speed: bool = False) -> PredictorFactory:
    """Makes AircraftPredictor copies of one aircraft that share one set of propeller
    tables."""
    propeller = Propeller.from_vehicle(vehicle)
    return lambda faults_pct: AircraftPredictor(faults_pct, vehicle, propeller, aircraft,
                                                steady_engine_speed)


def residual_generator(settings: ResidualSettings,
                       model: FlownAircraft = NOMINAL) -> ResidualGenerator:
    """residual_node's generator from its settings (`vehicle` the aircraft its copies load),
    its models the aircraft a model calibration found (model; its air-data bias taken
    out)."""
    vehicle = load_vehicle(settings.vehicle)
    steady_engine_speed = not settings.engine_speed_measured
    return ResidualGenerator(
        aircraft_predictor_factory(vehicle, model, steady_engine_speed), settings.fault_names,
        settings.secant_step_pct, settings.tau_a_s, settings.sensitivity_period_s,
        settings.recovery_s, settings.wind_error_step_mps, model.sensor_bias,
        air_data_range=vehicle.air_data_range,
        unmeasured=frozenset({"engine_speed"} if steady_engine_speed else ()),
        tau_a_pitot_s=settings.tau_a_pitot_s,
    )


def residual_sampler(settings: ResidualSettings,
                     model: FlownAircraft = NOMINAL) -> ResidualSampler:
    """residual_node's generator (residual_generator) on its update grid
    (update_period_s)."""
    return ResidualSampler(residual_generator(settings, model), settings.update_period_s)
