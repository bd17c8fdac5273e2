"""recorder_node: records every topic of the graph into a rosbag2 directory (MCAP).

Topics are discovered while the node runs and subscribed raw (no decoding), with the
reliability their publishers offer and keep-all history, so that a fast simulation loses
nothing. Timestamps are the receive time on the node's clock: simulation time when started
with use_sim_time (as demo.sh and bringup.sh start it), wall time otherwise. Each topic's
publishers' QoS profiles go into metadata.yaml. On SIGINT the recording is closed properly;
the per-topic counts are logged.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

from rclpy.clock import Clock, ClockType
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosbags.interfaces import (
    Qos,
    QosDurability,
    QosHistory,
    QosLiveliness,
    QosReliability,
    QosTime,
)
from uav_sim.ros.node_tools import ParameterSpec, declare_parameters, run_node

from uav_fault_estimator.analysis.recording import Recording, project_typestore

INFINITE_QOS_S, INFINITE_QOS_NS = 2147483647, 4294967295  # rosbag2's "infinite" duration
PARAMETERS = {
    "output_dir": ParameterSpec("the rosbag2 directory to create (it must not exist yet)"),
    "discovery_period_s": ParameterSpec(
        "how often new topics are looked for [s, wall time]", 0.01, 60.0),
}


def message_class(type_name: str) -> type:
    """The Python class of a ROS type name such as `std_msgs/msg/Header`."""
    package, _, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


def bag_qos(profile: QoSProfile) -> Qos:
    """A publisher's QoS profile as rosbag2's metadata writes it (the policies' values are
    rmw's in both)."""
    return Qos(
        history=QosHistory(profile.history.value), depth=profile.depth,
        reliability=QosReliability(profile.reliability.value),
        durability=QosDurability(profile.durability.value),
        deadline=_qos_time(profile.deadline), lifespan=_qos_time(profile.lifespan),
        liveliness=QosLiveliness(profile.liveliness.value),
        liveliness_lease_duration=_qos_time(profile.liveliness_lease_duration),
        avoid_ros_namespace_conventions=profile.avoid_ros_namespace_conventions)


def _qos_time(duration: Duration) -> QosTime:
    """A QoS duration; rmw's "infinite" (and anything past rosbag2's largest) as rosbag2
    writes infinite."""
    seconds, nanoseconds = divmod(duration.nanoseconds, 1_000_000_000)
    if seconds >= INFINITE_QOS_S:
        return QosTime(sec=INFINITE_QOS_S, nsec=INFINITE_QOS_NS)
    return QosTime(sec=seconds, nsec=nanoseconds)


def subscription_qos(reliable: bool) -> QoSProfile:
    return QoSProfile(
        history=HistoryPolicy.KEEP_ALL,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.VOLATILE,
    )


class RecorderNode(Node):
    """Thin adapter: discovery, raw subscriptions, one Recording."""

    def __init__(self) -> None:
        super().__init__("recorder_node")
        self.parameters = declare_parameters(
            self, "uav_fault_estimator", "recorder_node.yaml", PARAMETERS)
        output = Path(self.parameters["output_dir"])
        if not self.parameters["output_dir"] or output.exists():
            raise ValueError(f"output_dir '{output}' must be given and must not exist")
        self.recording = Recording(output, project_typestore())
        # wall time: with use_sim_time the node's clock stands still until /clock runs
        self.create_timer(self.parameters["discovery_period_s"], self.discover,
                          clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.discover()

    def discover(self) -> None:
        for topic, types in self.get_topic_names_and_types():
            if topic in self.recording.connections or not types:
                continue
            publishers = self.get_publishers_info_by_topic(topic)
            if not publishers:  # only subscribed to (e.g. /clock, by our own sim time) so far:
                continue        # nothing to record yet; its QoS comes with its publishers
            try:
                self.recording.add_topic(topic, types[0],
                                         [bag_qos(info.qos_profile) for info in publishers])
                message_type = message_class(types[0])
            except (ValueError, AttributeError, ModuleNotFoundError) as error:
                self.get_logger().warning(f"not recording {topic}: {error}", once=True)
                continue
            reliable = all(info.qos_profile.reliability == ReliabilityPolicy.RELIABLE
                           for info in publishers)
            self.create_subscription(
                message_type, topic,
                lambda data, topic=topic: self.recording.write(
                    topic, self.get_clock().now().nanoseconds, data),
                subscription_qos(reliable), raw=True,
            )

    def destroy_node(self) -> None:
        self.recording.close()
        counts = ", ".join(f"{topic} {count}" for topic, count in
                           sorted(self.recording.counts.items()))
        self.get_logger().info(f"recording closed in {self.recording.path}: {counts}")
        super().destroy_node()


def main(args: list[str] | None = None) -> int:
    return run_node("recorder_node", RecorderNode, args=args)


if __name__ == "__main__":
    sys.exit(main())
