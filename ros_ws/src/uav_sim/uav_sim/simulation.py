"""The simulated flight: a vehicle in JSBSim, autopilot, guidance, wind and seeded faults.

`Simulation(scenario)` trims the aircraft at the scenario's start, then `step()` advances
one sensor period and returns a `Sample`: the measured state, controls and air data (through
the sensor model), the filtered wind, the seeded faults and the true values, as arrays in the
channel orders of uav_common.channels. No ROS here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import jsbsim
import numpy as np
from uav_aircraft.fdm import (
    JSBSIM_DT_S,
    KG_PER_LB,
    M_PER_FT,
    THROTTLE_OUTPUT,
    create_fdm,
    property_nodes,
    set_faults,
    set_stuck_positions,
)
from uav_aircraft.frames import north_east_m
from uav_aircraft.propeller import Propeller
from uav_aircraft.trim import Trim, start_trimmed, trim_level_flight
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import (
    AIR_DATA_CHANNELS,
    FAULT_NAMES,
    SETPOINT_FIELDS,
    STATE_CHANNELS,
    STUCK_SURFACE_FAULT_NAMES,
    VANE_CHANNELS,
)

from uav_sim.autopilot import Autopilot, FlightState
from uav_sim.guidance import WaypointGuidance
from uav_sim.manoeuvres import excitation
from uav_sim.mpc_guidance import MpcGuidance
from uav_sim.scenario import Scenario
from uav_sim.sensors import SensorModel
from uav_sim.wind import (
    FROM_WIND,
    FilteredWind,
    GustProperties,
    background_wind_ned_mps,
    start_wind,
    total_wind_ned_mps,
    von_karman_turbulence,
)

CONTROL_STEPS = 4  # autopilot and the from_wind gusts at 120 Hz: every 4th JSBSim step
SENSOR_RATE_HZ = 20.0  # the sensors' default sample rate
# Random streams of the scenario seed: one per purpose, so that one's draws never shift
# another's (flying without air data leaves the turbulence and state noise as they were).
TURBULENCE_STREAM, STATE_SENSOR_STREAM, AIR_DATA_SENSOR_STREAM = 1, 2, 3
ENGINE_SPIN_UP_S = 3.0
# What the control loop reads and writes at 120 Hz, in _control's order (nodes found once).
CONTROL_READS = (
    "position/h-sl-meters", "velocities/v-down-fps", "velocities/vt-fps", "attitude/phi-rad",
    "attitude/theta-rad", "aero/beta-rad", "velocities/p-rad_sec", "velocities/q-rad_sec",
    "velocities/r-rad_sec", "velocities/v-north-fps", "velocities/v-east-fps",
    "position/lat-geod-rad", "position/long-gc-rad",
)
CONTROL_WRITES = ("fcs/elevator-cmd-norm", "fcs/aileron-cmd-norm", "fcs/rudder-cmd-norm",
                  "fcs/throttle-cmd-norm")
STATE_INTEGRATORS = tuple(
    f"simulation/integrator/{kind}/{motion}"
    for kind in ("rate", "position")
    for motion in ("rotational", "translational")
)


def spin_up_engine(fdm: jsbsim.FGFDMExec, duration_s: float = ENGINE_SPIN_UP_S) -> None:
    """Run the engine to its steady speed with the aircraft held at its initial state.

    JSBSim's propeller starts at rest, where its torque reaction P / max(0.01, omega) is
    enormous. With the state integrators set to none (0) the aircraft stays put while the
    engine and propeller run; their speed then matches the trim's to 0.01 rpm (measured).
    """
    saved = {name: fdm[name] for name in STATE_INTEGRATORS}
    for name in STATE_INTEGRATORS:
        fdm[name] = 0
    for _ in range(round(duration_s / JSBSIM_DT_S)):
        fdm.run()
    for name, integrator in saved.items():
        fdm[name] = integrator


@dataclass(frozen=True)
class Sample:
    """One sensor sample. Arrays follow STATE_CHANNELS, CONTROL_CHANNELS, AIR_DATA_CHANNELS
    and FAULT_NAMES; measured values are NaN where a sensor dropout is active."""

    time_s: float
    state: np.ndarray  # measured
    controls: np.ndarray  # measured surface positions, commanded throttle and engine
    air_data: np.ndarray | None  # measured; None without air data on board
    wind_filtered_ned_mps: np.ndarray  # the paper's w_hat, from the true wind
    seeded_faults_pct: np.ndarray
    true_state: np.ndarray
    true_controls: np.ndarray
    true_air_data: np.ndarray  # JSBSim's airspeed [m/s], alpha and beta [rad]
    wind_ned_mps: np.ndarray  # the true wind, background plus turbulence
    position_ne_m: np.ndarray  # true north, east of the start [m]
    # the autopilot's latest setpoints, SETPOINT_FIELDS order (roll, pitch [rad]; its
    # altitude hold commands no vertical velocity: NaN); NaN before its first command
    setpoints: np.ndarray


class Simulation:
    """Flies a scenario at a sensor rate that divides JSBSim's 480 Hz."""

    def __init__(self, scenario: Scenario, sensor_rate_hz: float = SENSOR_RATE_HZ) -> None:
        steps = round(1.0 / (JSBSIM_DT_S * sensor_rate_hz))
        if sensor_rate_hz <= 0 or not math.isclose(steps * JSBSIM_DT_S * sensor_rate_hz, 1.0):
            raise ValueError(
                f"sensor rate {sensor_rate_hz:g} Hz must divide the simulation rate "
                f"{1.0 / JSBSIM_DT_S:g} Hz (for example 10, 20, 40, 60 or 120)"
            )
        self.scenario = scenario
        self.steps_per_sample = steps
        self.period_s = steps * JSBSIM_DT_S
        self.sample_count = 0
        self.vehicle = load_vehicle(scenario.vehicle)
        self.fdm = create_fdm(self.vehicle, aircraft=scenario.aircraft)
        set_stuck_positions(self.fdm, {fault.name: fault.position for fault in scenario.faults
                                       if fault.name in STUCK_SURFACE_FAULT_NAMES})
        self.trim = self._start()
        self._reads = [node.get_double_value for node in property_nodes(self.fdm, CONTROL_READS)]
        self._writes = [node.set_double_value
                        for node in property_nodes(self.fdm, CONTROL_WRITES)]
        self._gusts = GustProperties(self.fdm)
        # North-east origin: where the flight starts. The engine spin-up held the aircraft
        # fixed in inertial space while the earth turned (about 250 m east per second at 55 N).
        self.origin_rad = (self.fdm["position/lat-geod-rad"], self.fdm["position/long-gc-rad"])
        self.autopilot = Autopilot(
            self.trim, scenario.initial.altitude_m, scenario.initial.airspeed_mps,
            self.vehicle.autopilot, self.vehicle.surface_limit_rad)
        self.guidance = (
            MpcGuidance(scenario.waypoints_ne_m, self.autopilot.gains.roll_limit_rad,
                        scenario.guidance.mpc)
            if scenario.guidance.method == "mpc" else WaypointGuidance(scenario.waypoints_ne_m))
        self.filtered_wind = FilteredWind(scenario.wind.filter_time_constant_s, self.period_s)
        self.sensors = SensorModel(
            scenario.sensors.noise, self.period_s, self.origin_rad[0],
            np.random.default_rng([scenario.seed, STATE_SENSOR_STREAM]),
            np.random.default_rng([scenario.seed, AIR_DATA_SENSOR_STREAM]),
            scenario.aircraft.sensor_bias)
        self.turbulence = None
        if scenario.wind.turbulence == FROM_WIND:
            self.turbulence = von_karman_turbulence(
                self.fdm, scenario.wind, scenario.initial.airspeed_mps,
                scenario.initial.altitude_m, CONTROL_STEPS * JSBSIM_DT_S,
                np.random.default_rng([scenario.seed, TURBULENCE_STREAM]))
        self._faults_set: dict[str, float] | None = None  # what the aircraft holds now
        self._setpoints = np.full(len(SETPOINT_FIELDS), math.nan)  # none commanded yet
        self._latest = self._sample()

    def _start(self) -> Trim:
        """Trim in calm air, start in the background wind, spin the engine up, turbulence on."""
        initial = self.scenario.initial
        fdm = self.fdm
        fdm["ic/lat-geod-deg"] = initial.latitude_deg
        fdm["ic/long-gc-deg"] = initial.longitude_deg
        fdm["ic/h-sl-ft"] = initial.altitude_m / M_PER_FT
        fdm["fcs/mixture-cmd-norm"] = 1.0
        fdm["fcs/ignition-cmd"] = 1.0
        trim = trim_level_flight(fdm, initial.airspeed_mps, self.vehicle,
                                 Propeller.from_vehicle(self.vehicle))
        wind = self.scenario.wind
        start_trimmed(
            fdm,
            trim,
            initial.airspeed_mps,
            math.radians(initial.heading_deg),
            background_wind_ned_mps(wind),
        )
        fdm["fcs/throttle-cmd-norm"] = trim.throttle
        spin_up_engine(fdm)
        start_wind(fdm, wind, self.scenario.seed)
        return trim

    @property
    def time_s(self) -> float:
        return self.sample_count * self.period_s

    @property
    def finished(self) -> bool:
        return self.time_s >= self.scenario.duration_s - 0.5 * self.period_s

    @property
    def guidance_fallbacks(self) -> int:
        """Guidance samples the MPC's QP was not solved, flown on the vector field instead
        (0 with the vector field itself)."""
        return self.guidance.fallbacks if isinstance(self.guidance, MpcGuidance) else 0

    def sample(self) -> Sample:
        """The latest sample (the initial one before the first step)."""
        return self._latest

    def step(self) -> Sample:
        """Advance one sensor period and return the new sample."""
        fdm = self.fdm
        for step in range(self.steps_per_sample):
            if step % CONTROL_STEPS == 0:
                time_s = self.time_s + step * JSBSIM_DT_S
                faults_pct = self.scenario.faults_pct(time_s)
                if faults_pct != self._faults_set:  # held most of the flight: not rewritten
                    set_faults(fdm, faults_pct)
                    self._faults_set = faults_pct
                if self.turbulence is not None:
                    self._gusts.set(*self.turbulence.step())
                self._control(CONTROL_STEPS * JSBSIM_DT_S, time_s)
            fdm.run()
        self.sample_count += 1
        self._latest = self._sample()
        return self._latest

    def _control(self, dt_s: float, time_s: float) -> None:
        """One autopilot period of dt_s [s] at time_s [s] (a manoeuvre's input changes at
        the control rate, not the sensor rate)."""
        (altitude_m, down_fps, airspeed_fps, roll_rad, pitch_rad, sideslip_rad, p_radps, q_radps,
         r_radps, north_fps, east_fps, latitude_rad, longitude_rad) = [
            read() for read in self._reads]
        state = FlightState(
            altitude_m=altitude_m,
            climb_rate_mps=-down_fps * M_PER_FT,
            airspeed_mps=airspeed_fps * M_PER_FT,
            roll_rad=roll_rad,
            pitch_rad=pitch_rad,
            sideslip_rad=sideslip_rad,
            body_rates_radps=(p_radps, q_radps, r_radps),
        )
        roll_cmd_rad = self.guidance.roll_command(
            north_east_m(latitude_rad, longitude_rad, self.origin_rad),
            np.array([north_fps, east_fps]) * M_PER_FT,
            dt_s,
        )
        self.autopilot.airspeed_cmd_mps, self.autopilot.altitude_cmd_m = (
            self.scenario.commanded(self.time_s))
        commands = self.autopilot.update(state, roll_cmd_rad, dt_s, excitation(
            self.scenario.manoeuvres, time_s, self.vehicle.surface_limit_rad))
        self._setpoints = np.array([commands.roll_cmd_rad, commands.pitch_cmd_rad, math.nan])
        limit = self.vehicle.surface_limit_rad
        set_elevator, set_aileron, set_rudder, set_throttle = self._writes
        set_elevator(commands.elevator_rad / limit)
        set_aileron(commands.aileron_rad / limit)
        set_rudder(commands.rudder_rad / limit)
        set_throttle(commands.throttle)

    def _position_ne_m(self) -> np.ndarray:
        return north_east_m(
            self.fdm["position/lat-geod-rad"], self.fdm["position/long-gc-rad"], self.origin_rad
        )

    def _sample(self) -> Sample:
        fdm = self.fdm
        true_state = np.array(
            [
                fdm["position/lat-geod-rad"],
                fdm["position/long-gc-rad"],
                fdm["position/h-sl-meters"],
                fdm["attitude/phi-rad"],
                fdm["attitude/theta-rad"],
                fdm["attitude/psi-rad"],
                fdm["velocities/v-north-fps"] * M_PER_FT,
                fdm["velocities/v-east-fps"] * M_PER_FT,
                fdm["velocities/v-down-fps"] * M_PER_FT,
                fdm["velocities/p-rad_sec"],
                fdm["velocities/q-rad_sec"],
                fdm["velocities/r-rad_sec"],
                fdm["propulsion/tank/contents-lbs"] * KG_PER_LB,
                fdm["propulsion/engine/engine-rpm"],
            ]
        )
        true_controls = np.array(
            [
                fdm["fcs/flap-pos-rad"],
                fdm["fcs/elevator-pos-rad"],
                fdm["fcs/aileron-pos-rad"],
                fdm["fcs/rudder-pos-rad"],
                fdm[THROTTLE_OUTPUT],
                fdm["fcs/mixture-cmd-norm"],
                fdm["fcs/ignition-cmd"],
            ]
        )
        true_air_data = np.array(
            [fdm["velocities/vt-fps"] * M_PER_FT, fdm["aero/alpha-rad"], fdm["aero/beta-rad"]])
        state, controls, air_data = self.sensors.measure(true_state, true_controls,
                                                         true_air_data)
        dropped = self.scenario.dropped_channels(self.time_s)
        if not self.scenario.sensors.vanes:
            dropped |= set(VANE_CHANNELS)
        if dropped:
            state, air_data = state.copy(), air_data.copy()
            for channel in dropped:
                if channel in AIR_DATA_CHANNELS:
                    air_data[AIR_DATA_CHANNELS.index(channel)] = math.nan
                else:
                    state[STATE_CHANNELS.index(channel)] = math.nan
        faults = self.scenario.faults_pct(self.time_s)
        wind_ned_mps = total_wind_ned_mps(fdm)
        return Sample(
            time_s=self.time_s,
            state=state,
            controls=controls,
            air_data=air_data if self.scenario.sensors.air_data else None,
            wind_filtered_ned_mps=self.filtered_wind.update(wind_ned_mps),
            seeded_faults_pct=np.array([faults[name] for name in FAULT_NAMES]),
            true_state=true_state,
            true_controls=true_controls,
            true_air_data=true_air_data,
            wind_ned_mps=wind_ned_mps,
            position_ne_m=self._position_ne_m(),
            setpoints=self._setpoints.copy(),
        )
