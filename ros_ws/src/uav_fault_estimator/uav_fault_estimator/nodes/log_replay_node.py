"""log_replay_node: publishes a flight log as the project's streams, so that detector_node
runs unchanged on a real flight.

Reads the log once (flight_logs.replay: a PX4 ULog, a ROS 1 or 2 bag, a folder of per-topic
CSVs; the actuator outputs mapped to surfaces by the airframe file), resampled onto the
detector's grid, and publishes, stamped with the grid's times (relative names, the `qos` chosen):
`state` (AircraftState: the log's body rates and attitude, the channels no log carries
NaN), `controls` (ControlInputs: surfaces and throttle), `air_data` (AirData: the log's
airspeed, the angles NaN; only when the log has airspeed), `/clock` (the log's time, for
nodes with use_sim_time) and `/diagnostics`. Grid points where the log has a gap are
published too, with NaN: the detector skips them as it does offline. Paced like sim_node
(real_time_factor; 0: as fast as the subscribers acknowledge). Ends at the log's end with
exit status 0; a bad log, airframe or axes: one line, status 2.
"""

from __future__ import annotations

import sys
import time
from typing import Any

import rclpy
from rclpy.node import Node
from rosgraph_msgs.msg import Clock
from uav_common.ros.diagnostics import OK, WARN, Diagnostics
from uav_common.ros.messages import (
    air_data_message,
    controls_message,
    setpoints_message,
    stamp,
    state_message,
)
from uav_common.ros.node_life import run_node
from uav_common.ros.paced_publishing import PacedPublishers
from uav_common.ros.parameters import QOS_PARAMETER, ParameterSpec, declare_parameters
from uav_common.ros.qos import CLOCK_QOS, STREAM_QOS_PROFILES
from uav_fault_msgs.msg import AircraftState, AirData, AutopilotSetpoints, ControlInputs

from uav_fault_estimator.flight_logs.replay import load_replay

PARAMETERS = {
    "log": ParameterSpec("flight log (required): a PX4 .ulg, a ROS 1 .bag, a ROS 2 bag folder or a "
                         "folder of per-topic CSV files", ""),
    "airframe": ParameterSpec("airframe YAML mapping the log's actuator outputs to surfaces; "
                              "empty for a log that carries surfaces (the project's "
                              "recordings)", ""),
    "axes": ParameterSpec("the log's body axes, FRD or FLU; empty: the airframe's, else the "
                          "format's own", ""),
    # the detector acts on whole multiples of its calibration's period only
    "sample_period_s": ParameterSpec("period of the grid the log is resampled onto: the "
                                     "detector calibration's [s]", 0.2, 0.01, 10.0),
    "real_time_factor": ParameterSpec(
        "log seconds per wall second; 0: as fast as subscribers keep up", 1.0, 0.0, 1000.0,
        live=True),
    "wait_for_subscribers": ParameterSpec(
        "start once state has this many subscriptions and discovery settled (1: "
        "detector_node beside it)", 1, 0, 100),
    "qos": QOS_PARAMETER,
}


class LogReplayNode(Node):
    """Thin adapter: parameters in, the log on the grid (core), rows to messages, pacing."""

    def __init__(self) -> None:
        super().__init__("log_replay_node")
        self.parameters = declare_parameters(self, PARAMETERS, self.change_pace)
        p = self.parameters
        if not p["log"]:
            raise ValueError("no flight log given: -p log:=FLIGHT.ulg (and -p "
                             "airframe:=AIRFRAME.yaml for actuator outputs)")
        self.replay = load_replay(p["log"], p["airframe"] or None, p["axes"] or None,
                                  p["sample_period_s"])
        for line in dict.fromkeys(self.replay.inputs.warnings):  # each once, in order
            self.get_logger().warning(line)
        qos = STREAM_QOS_PROFILES[p["qos"]]
        publishers = [self.create_publisher(AircraftState, "state", qos),
                      self.create_publisher(ControlInputs, "controls", qos)]
        if self.replay.air_data is not None:
            publishers.append(self.create_publisher(AirData, "air_data", qos))
        if self.replay.setpoints is not None:
            publishers.append(self.create_publisher(AutopilotSetpoints, "autopilot_setpoints",
                                                    qos))
        self.paced = PacedPublishers(self, publishers)
        self.paced.check_factor(p["real_time_factor"])
        self.clock_publisher = self.create_publisher(Clock, "/clock", CLOCK_QOS)
        times_s = self.replay.inputs.times_s
        self.clock_s = float(times_s[0])  # the log's time last published on /clock [s]
        # a source: no inputs; stamped with the log's time it publishes
        self.diagnostics = Diagnostics(self, silent_after_s=None, clock_s=lambda: self.clock_s)
        self.get_logger().info(
            f"log {self.replay.source}: {times_s.size} samples every {p['sample_period_s']:g} s "
            f"from {times_s[0]:g} to {times_s[-1]:g} s, real-time factor "
            f"{p['real_time_factor']:g}")

    def publish(self, row: int) -> None:
        """Publish the grid's row-th sample on every stream, then the clock."""
        inputs = self.replay.inputs
        time_s = float(inputs.times_s[row])
        messages = [state_message(time_s, inputs.state[row]),
                    controls_message(time_s, inputs.controls[row])]
        if self.replay.air_data is not None:
            messages.append(air_data_message(time_s, self.replay.air_data[row]))
        if self.replay.setpoints is not None:
            messages.append(setpoints_message(time_s, self.replay.setpoints[row]))
        for publisher, message in zip(self.paced.publishers, messages, strict=True):
            publisher.publish(message)
        self.clock_publisher.publish(Clock(clock=stamp(time_s)))
        self.clock_s = time_s

    def replay_log(self) -> None:
        """Publish every row of the grid, paced by the real-time factor, until the log's
        end, and wait until the subscribers have it all."""
        times_s = self.replay.inputs.times_s
        started = time.monotonic()
        self.paced.start(float(times_s[0]))
        for row in range(times_s.size):
            if not rclpy.ok():
                return
            self.publish(row)
            self.paced.pace(float(times_s[row]), row + 1, self.parameters["real_time_factor"])
            self.report(row, time.monotonic() - started)
            rclpy.spin_once(self, timeout_sec=0.0)  # parameter services: a new pace
        self.paced.wait_until_delivered()
        self.get_logger().info(
            f"log {self.replay.source} replayed to {times_s[-1]:g} s in "
            f"{time.monotonic() - started:.1f} s of wall time")
        self.diagnostics.publish_last()  # the replay's last status, before the node ends

    def change_pace(self, changes: dict[str, Any]) -> None:
        """A new real-time factor, counted from the next sample on."""
        self.paced.check_factor(changes["real_time_factor"])
        self.paced.restart()
        self.get_logger().info(f"real-time factor {changes['real_time_factor']:g}")

    def report(self, row: int, wall_s: float) -> None:
        """Diagnostics: where in the log, how fast, and whether the log needed warnings."""
        inputs = self.replay.inputs
        elapsed_s = inputs.times_s[row] - inputs.times_s[0]
        values = {
            "log": self.replay.source,
            "log_time_s": f"{inputs.times_s[row]:.2f}",
            "end_s": f"{inputs.times_s[-1]:.2f}",
            "real_time_factor": f"{elapsed_s / wall_s:.1f}" if wall_s > 0 else "-",
            "warnings": len(set(inputs.warnings)),
        }
        if inputs.warnings:
            self.diagnostics.update(WARN, "replaying; the log needed warnings (see the node's "
                                    "log)", values)
        else:
            self.diagnostics.update(OK, "replaying", values)


def replay(node: LogReplayNode) -> None:
    node.paced.wait_for_subscribers(node.parameters["wait_for_subscribers"])
    node.replay_log()


def main(args: list[str] | None = None) -> int:
    return run_node("log_replay_node", LogReplayNode, replay, args)


if __name__ == "__main__":
    sys.exit(main())
