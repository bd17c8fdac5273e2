"""sim_node: flies a scenario in the core Simulation and publishes it at the sensor rate.

Publishes (relative names, the `qos` chosen): `state` (AircraftState), `controls`
(ControlInputs), `air_data` (AirData; only when the scenario's aircraft carries air data),
`wind/filtered` (WindEstimate), `autopilot_setpoints` (AutopilotSetpoints: its autopilot's
commanded roll and pitch); the simulation's truth `faults/seeded` (FaultVector) and
`wind/true` (geometry_msgs/Vector3Stamped, NED m/s); and `/clock` (the simulation time, for
nodes with use_sim_time) and `/diagnostics`. Run with use_sim_time, it follows the domain's
`/clock` instead of publishing it (a second vehicle in the same domain): each step waits
until the clock has reached its time, so every vehicle flies on the one clock. Measurements
go through the sensor model (uav_sim.sensors) unless the scenario says `sensors: {noise:
false}`. Its /diagnostics say which vehicle flies (`vehicle`) and how the flown aircraft
differs from the model (`flown_aircraft`: JSON of the scenario's aircraft block where it
differs, {} for the model itself), so that a recording keeps what was flown. Ends by itself
at the scenario's end, with exit status 0; a bad scenario or parameter ends it before it
starts, status 2.
"""

from __future__ import annotations

import json
import math
import sys
import time
from typing import Any

import rclpy
from geometry_msgs.msg import Vector3Stamped
from rclpy.node import Node
from rosgraph_msgs.msg import Clock
from uav_aircraft.flown_aircraft import DIAGNOSTIC_KEY
from uav_aircraft.vehicles import vehicle_names
from uav_common.channels import AIR_DATA_CHANNELS, FAULT_NAMES, STATE_CHANNELS
from uav_common.health import GUIDANCE_FALLBACKS_KEY, GUIDANCE_KEY, VEHICLE_KEY
from uav_common.message_fields import stamp_seconds
from uav_common.ros.diagnostics import OK, WARN, Diagnostics
from uav_common.ros.messages import (
    air_data_message,
    controls_message,
    fault_vector_message,
    setpoints_message,
    stamp,
    state_message,
    true_wind_message,
    wind_message,
)
from uav_common.ros.node_life import run_node
from uav_common.ros.paced_publishing import PacedPublishers
from uav_common.ros.parameters import QOS_PARAMETER, ParameterSpec, declare_parameters
from uav_common.ros.qos import CLOCK_QOS, STREAM_QOS_PROFILES
from uav_common.sample_grid import GRID_TOLERANCE_S
from uav_fault_msgs.msg import (
    AircraftState,
    AirData,
    AutopilotSetpoints,
    ControlInputs,
    FaultVector,
    WindEstimate,
)

from uav_sim.scenario import default_scenario_path, load_scenario
from uav_sim.simulation import SENSOR_RATE_HZ, Sample, Simulation

PARAMETERS = {
    "scenario": ParameterSpec("scenario YAML file; empty: the shipped scenarios/default.yaml",
                              ""),
    "vehicle": ParameterSpec("the aircraft flown; empty: the scenario's `vehicle`, which a "
                             "name given here must equal", "", choices=("", *vehicle_names()),
                             empty_choice="the scenario's"),
    # at least 1 Hz; at most JSBSim's own 480 Hz (and a divisor of it: Simulation checks)
    "sensor_rate_hz": ParameterSpec("rate of every published stream and of /clock, a divisor "
                                    "of 480 [Hz]", SENSOR_RATE_HZ,
                                    1.0, 480.0),
    "real_time_factor": ParameterSpec(
        "simulated seconds per wall second; 0: as fast as subscribers keep up", 1.0, 0.0, 1000.0,
        live=True),
    # longer by default than a leading simulator's own waits for acknowledgements (10 s)
    "clock_stall_s": ParameterSpec(
        "with use_sim_time: how long the followed /clock may stand still once running before "
        "the node gives up [s, wall time]", 30.0, 0.1, 3600.0),
    "wait_for_subscribers": ParameterSpec(
        "start once state has this many subscriptions and discovery settled", 0, 0, 100),
    "qos": QOS_PARAMETER,
}
CLOCK_POLL_S = 0.05  # wall time per wait for /clock when following it


class SimNode(Node):
    """Thin adapter: parameters in, Simulation steps, arrays to messages, diagnostics."""

    def __init__(self) -> None:
        super().__init__("sim_node")
        self.parameters = declare_parameters(self, PARAMETERS, self.change_pace)
        scenario_path = self.parameters["scenario"] or str(default_scenario_path())
        self.scenario = load_scenario(scenario_path)
        vehicle = self.parameters["vehicle"]
        if vehicle and vehicle != self.scenario.vehicle:
            raise ValueError(f"parameter vehicle is {vehicle!r}, but the scenario {scenario_path} "
                             f"flies {self.scenario.vehicle!r}")
        self.simulation = Simulation(
            self.scenario, sensor_rate_hz=self.parameters["sensor_rate_hz"]
        )
        qos = STREAM_QOS_PROFILES[self.parameters["qos"]]
        self.stream_publishers = [
            self.create_publisher(AircraftState, "state", qos),
            self.create_publisher(ControlInputs, "controls", qos),
            self.create_publisher(WindEstimate, "wind/filtered", qos),
            self.create_publisher(FaultVector, "faults/seeded", qos),
            self.create_publisher(Vector3Stamped, "wind/true", qos),
            self.create_publisher(AutopilotSetpoints, "autopilot_setpoints", qos),
        ]
        self.air_data_publisher = None
        if self.scenario.sensors.air_data:
            self.air_data_publisher = self.create_publisher(AirData, "air_data", qos)
            self.stream_publishers.append(self.air_data_publisher)
        self.paced = PacedPublishers(self, self.stream_publishers)
        # one /clock per domain: a simulator on use_sim_time follows it (wait_for_clock)
        self.follows_clock = self.get_parameter("use_sim_time").value
        if not self.follows_clock:
            self.paced.check_factor(self.parameters["real_time_factor"])
        self.clock_publisher = (None if self.follows_clock else
                                self.create_publisher(Clock, "/clock", CLOCK_QOS))
        # A follower's steps wait on a reliable /clock subscription of its own: use_sim_time's
        # is best effort, and may miss the last /clock of a simulator that then ends.
        self.followed_clock_s = 0.0
        if self.follows_clock:
            self.create_subscription(Clock, "/clock", self.on_clock, CLOCK_QOS)
        # a source: no inputs; stamped with the simulation time it publishes
        self.diagnostics = Diagnostics(self, silent_after_s=None,
                                       clock_s=lambda: self.simulation.time_s)
        self.flown_aircraft = json.dumps(self.scenario.aircraft.differences())  # {}: the model
        self.get_logger().info(
            f"scenario '{self.scenario.name}' from {scenario_path}: {self.scenario.duration_s:g} s "
            f"at {self.parameters['sensor_rate_hz']:g} Hz, "
            + ("following /clock" if self.follows_clock else
               f"real-time factor {self.parameters['real_time_factor']:g}")
        )

    def publish(self, sample: Sample) -> None:
        """Publish one sensor sample on every stream, then the clock."""
        time_s = sample.time_s
        messages = [
            state_message(time_s, sample.state),
            controls_message(time_s, sample.controls),
            wind_message(
                time_s, sample.wind_filtered_ned_mps, self.scenario.wind.filter_time_constant_s
            ),
            fault_vector_message(time_s, FAULT_NAMES, sample.seeded_faults_pct),
            true_wind_message(time_s, sample.wind_ned_mps),
            setpoints_message(time_s, sample.setpoints),
        ]
        if self.air_data_publisher is not None:
            messages.append(air_data_message(time_s, sample.air_data))
        for publisher, message in zip(self.stream_publishers, messages, strict=True):
            publisher.publish(message)
        if self.clock_publisher is not None:
            self.clock_publisher.publish(Clock(clock=stamp(time_s)))

    def wait_for_clock(self, time_s: float) -> None:
        """Block until the domain's /clock has reached time_s [s] (within the grid's
        tolerance), handling callbacks meanwhile. ValueError (status 2) when the clock,
        once running, stands still for clock_stall_s: its simulator ended before this
        scenario's end, so the scenarios do not last as long."""
        stall_s = self.parameters["clock_stall_s"]
        clock_s, changed_at = self.clock_s(), time.monotonic()
        while rclpy.ok() and clock_s < time_s - GRID_TOLERANCE_S:
            rclpy.spin_once(self, timeout_sec=CLOCK_POLL_S)
            if self.clock_s() != clock_s:
                clock_s, changed_at = self.clock_s(), time.monotonic()
            elif clock_s > 0 and time.monotonic() - changed_at > stall_s:
                raise ValueError(
                    f"the /clock it follows stood still at {clock_s:g} s for "
                    f"{stall_s:g} s of wall time, before this scenario's end at "
                    f"{self.scenario.duration_s:g} s: the vehicles' scenarios must last as "
                    "long")

    def on_clock(self, message: Clock) -> None:
        self.followed_clock_s = stamp_seconds(message.clock)

    def clock_s(self) -> float:
        """The followed /clock [s], as the node's own reliable subscription last heard it."""
        return self.followed_clock_s

    def fly(self) -> None:
        """Step and publish until the scenario's end, paced by the real-time factor."""
        started = time.monotonic()
        self.paced.start(self.simulation.time_s)
        self.publish(self.simulation.sample())
        while rclpy.ok() and not self.simulation.finished:
            if self.follows_clock:
                self.wait_for_clock(self.simulation.time_s + self.simulation.period_s)
            sample = self.simulation.step()
            self.publish(sample)
            rate = 0.0 if self.follows_clock else self.parameters["real_time_factor"]
            self.paced.pace(sample.time_s, self.simulation.sample_count, rate)
            self.report(sample, time.monotonic() - started)
            rclpy.spin_once(self, timeout_sec=0.0)
        # the followers' last /clock too, or they would wait for it in vain
        self.paced.wait_until_delivered(also=[self.clock_publisher] if self.clock_publisher
                                        else [])
        self.diagnostics.publish_last()  # the flight's whole CPU time, before the node ends
        self.get_logger().info(
            f"scenario '{self.scenario.name}' finished at {self.simulation.time_s:g} s of "
            f"simulation time after {time.monotonic() - started:.1f} s of wall time"
        )

    def change_pace(self, changes: dict[str, Any]) -> None:
        """A new real-time factor, counted from the next step on."""
        self.paced.check_factor(changes["real_time_factor"])
        self.paced.restart()
        self.get_logger().info(f"real-time factor {changes['real_time_factor']:g}")

    def report(self, sample: Sample, wall_s: float) -> None:
        channels = list(zip(STATE_CHANNELS, sample.state, strict=True))
        if sample.air_data is not None:
            channels += zip(AIR_DATA_CHANNELS, sample.air_data, strict=True)
        missing = [name for name, value in channels if not math.isfinite(value)]
        values = {
            "sim_time_s": f"{sample.time_s:.2f}",
            "real_time_factor": f"{sample.time_s / wall_s:.1f}" if wall_s > 0 else "-",
            "scenario": self.scenario.name,
            VEHICLE_KEY: self.scenario.vehicle,
            DIAGNOSTIC_KEY: self.flown_aircraft,
            "missing_channels": ",".join(missing) or "none",
            GUIDANCE_KEY: self.scenario.guidance.method,
            GUIDANCE_FALLBACKS_KEY: self.simulation.guidance_fallbacks,
        }
        if missing:
            self.diagnostics.update(WARN, "sensor dropout: " + ", ".join(missing), values)
        elif self.simulation.guidance_fallbacks:
            self.diagnostics.update(WARN, "MPC guidance: a QP not solved, that step flown on "
                                    "the vector field", values)
        else:
            self.diagnostics.update(OK, "flying", values)


def fly(node: SimNode) -> None:
    node.paced.wait_for_subscribers(node.parameters["wait_for_subscribers"])
    node.fly()


def main(args: list[str] | None = None) -> int:
    return run_node("sim_node", SimNode, fly, args)


if __name__ == "__main__":
    sys.exit(main())
