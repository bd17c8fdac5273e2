"""recorder_node: records every topic of the graph into a rosbag2 directory (MCAP).

Topics are discovered while the node runs and subscribed raw (no decoding), with the
reliability their publishers offer and keep-all history, so that a fast simulation loses
nothing. Timestamps are the receive time. On SIGINT the recording is closed properly; the
per-topic counts are logged.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from uav_sim.ros.node_tools import ParameterSpec, declare_parameters, run_node

from uav_fault_estimator.analysis.recording import Recording, project_typestore

PARAMETERS = {
    "output_dir": ParameterSpec("the rosbag2 directory to create (it must not exist yet)"),
    "discovery_period_s": ParameterSpec(
        "how often new topics are looked for [s, wall time]", 0.01, 60.0),
}


def message_class(type_name: str) -> type:
    """The Python class of a ROS type name such as `std_msgs/msg/Header`."""
    package, _, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


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
        self.create_timer(self.parameters["discovery_period_s"], self.discover)
        self.discover()

    def discover(self) -> None:
        for topic, types in self.get_topic_names_and_types():
            if topic in self.recording.connections or not types:
                continue
            try:
                self.recording.add_topic(topic, types[0])
                message_type = message_class(types[0])
            except (ValueError, AttributeError, ModuleNotFoundError) as error:
                self.get_logger().warning(f"not recording {topic}: {error}", once=True)
                continue
            publishers = self.get_publishers_info_by_topic(topic)
            reliable = all(info.qos_profile.reliability == ReliabilityPolicy.RELIABLE
                           for info in publishers) if publishers else True
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
