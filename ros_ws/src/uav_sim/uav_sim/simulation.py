"""The simulated flight: JSBSim Aerosonde, autopilot, guidance, wind and seeded faults.

`Simulation(scenario)` trims the aircraft at the scenario's start, then `step()` advances
one sensor period and returns a `Sample`: the state, controls, filtered wind and seeded
faults as arrays in the channel orders of uav_sim.channels. No ROS here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import jsbsim
import numpy as np

from uav_sim.aircraft import (
    JSBSIM_DT_S,
    KG_PER_LB,
    M_PER_FT,
    SURFACE_LIMIT_RAD,
    create_fdm,
    set_faults,
)
from uav_sim.autopilot import Autopilot, FlightState
from uav_sim.channels import FAULT_NAMES, STATE_CHANNELS
from uav_sim.frames import north_east_m
from uav_sim.guidance import WaypointGuidance
from uav_sim.propeller import Propeller
from uav_sim.scenario import Scenario
from uav_sim.trim import Trim, start_trimmed, trim_level_flight
from uav_sim.wind import (
    FilteredWind,
    background_wind_ned_mps,
    start_wind,
    total_wind_ned_mps,
)

CONTROL_STEPS = 4  # autopilot at 120 Hz: every 4th JSBSim step
ENGINE_SPIN_UP_S = 3.0
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
    """One sensor sample. Arrays follow STATE_CHANNELS, CONTROL_CHANNELS and FAULT_NAMES."""

    time_s: float
    state: np.ndarray  # NaN where a sensor dropout is active
    controls: np.ndarray
    wind_filtered_ned_mps: np.ndarray
    seeded_faults_pct: np.ndarray
    wind_ned_mps: np.ndarray  # the true wind, background plus turbulence
    airspeed_mps: float
    position_ne_m: np.ndarray  # north, east of the start [m]


class Simulation:
    """Flies a scenario at a sensor rate that divides JSBSim's 480 Hz."""

    def __init__(self, scenario: Scenario, sensor_rate_hz: float = 20.0) -> None:
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
        self.fdm = create_fdm()
        self.trim = self._start()
        # North-east origin: where the flight starts. The engine spin-up held the aircraft
        # fixed in inertial space while the earth turned (about 250 m east per second at 55 N).
        self.origin_rad = (self.fdm["position/lat-geod-rad"], self.fdm["position/long-gc-rad"])
        self.autopilot = Autopilot(
            self.trim, scenario.initial.altitude_m, scenario.initial.airspeed_mps
        )
        self.guidance = WaypointGuidance(scenario.waypoints_ne_m)
        self.filtered_wind = FilteredWind(scenario.wind.filter_time_constant_s, self.period_s)
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
        trim = trim_level_flight(fdm, initial.airspeed_mps, Propeller.from_aircraft())
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

    def sample(self) -> Sample:
        """The latest sample (the initial one before the first step)."""
        return self._latest

    def step(self) -> Sample:
        """Advance one sensor period and return the new sample."""
        fdm = self.fdm
        for step in range(self.steps_per_sample):
            if step % CONTROL_STEPS == 0:
                time_s = self.time_s + step * JSBSIM_DT_S
                set_faults(fdm, self.scenario.faults_pct(time_s))
                self._control(CONTROL_STEPS * JSBSIM_DT_S)
            fdm.run()
        self.sample_count += 1
        self._latest = self._sample()
        return self._latest

    def _control(self, dt_s: float) -> None:
        fdm = self.fdm
        state = FlightState(
            altitude_m=fdm["position/h-sl-meters"],
            climb_rate_mps=-fdm["velocities/v-down-fps"] * M_PER_FT,
            airspeed_mps=fdm["velocities/vt-fps"] * M_PER_FT,
            roll_rad=fdm["attitude/phi-rad"],
            pitch_rad=fdm["attitude/theta-rad"],
            sideslip_rad=fdm["aero/beta-rad"],
            body_rates_radps=np.array(
                [
                    fdm["velocities/p-rad_sec"],
                    fdm["velocities/q-rad_sec"],
                    fdm["velocities/r-rad_sec"],
                ]
            ),
        )
        roll_cmd_rad = self.guidance.roll_command(
            self._position_ne_m(),
            np.array([fdm["velocities/v-north-fps"], fdm["velocities/v-east-fps"]]) * M_PER_FT,
        )
        commands = self.autopilot.update(state, roll_cmd_rad, dt_s)
        fdm["fcs/elevator-cmd-norm"] = commands.elevator_rad / SURFACE_LIMIT_RAD
        fdm["fcs/aileron-cmd-norm"] = commands.aileron_rad / SURFACE_LIMIT_RAD
        fdm["fcs/rudder-cmd-norm"] = commands.rudder_rad / SURFACE_LIMIT_RAD
        fdm["fcs/throttle-cmd-norm"] = commands.throttle

    def _position_ne_m(self) -> np.ndarray:
        return north_east_m(
            self.fdm["position/lat-geod-rad"], self.fdm["position/long-gc-rad"], self.origin_rad
        )

    def _sample(self) -> Sample:
        fdm = self.fdm
        state = np.array(
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
        for channel in self.scenario.dropped_channels(self.time_s):
            state[STATE_CHANNELS.index(channel)] = math.nan
        controls = np.array(
            [
                fdm["fcs/flap-pos-rad"],
                fdm["fcs/elevator-pos-rad"],
                fdm["fcs/aileron-pos-rad"],
                fdm["fcs/rudder-pos-rad"],
                fdm["fcs/throttle-cmd-norm"],
                fdm["fcs/mixture-cmd-norm"],
                fdm["fcs/ignition-cmd"],
            ]
        )
        faults = self.scenario.faults_pct(self.time_s)
        wind_ned_mps = total_wind_ned_mps(fdm)
        return Sample(
            time_s=self.time_s,
            state=state,
            controls=controls,
            wind_filtered_ned_mps=self.filtered_wind.update(wind_ned_mps),
            seeded_faults_pct=np.array([faults[name] for name in FAULT_NAMES]),
            wind_ned_mps=wind_ned_mps,
            airspeed_mps=fdm["velocities/vt-fps"] * M_PER_FT,
            position_ne_m=self._position_ne_m(),
        )
