"""recorder_node: records every topic of the graph into a rosbag2 directory (MCAP).

Topics are discovered while the node runs and subscribed raw (no decoding), with the
reliability their publishers offer and keep-all history, so that a fast simulation loses
nothing. Timestamps are the receive time on the node's clock: simulation time when started
with use_sim_time (as demo.sh and bringup.sh start it), wall time otherwise. Each topic's
publishers' QoS profiles go into metadata.yaml. Each topic's count so far is on /diagnostics.
On SIGINT (or SIGTERM) the messages that had arrived are written, the recording is closed
properly and the per-topic counts are logged.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.topic_endpoint_info import TopicEndpointInfo
from rosbags.interfaces import (
    Qos,
    QosDurability,
    QosHistory,
    QosLiveliness,
    QosReliability,
    QosTime,
)
from uav_common.ros.diagnostics import OK, Diagnostics
from uav_common.ros.node_life import run_node, spin
from uav_common.ros.parameters import ParameterSpec, declare_parameters

from uav_fault_estimator.nodes.raw_topics import RawTopics
from uav_fault_estimator.recording.project_bag import Recording, project_typestore

# Longest a stop waits while the recorder writes what had arrived [s, wall time]: a
# backlog of a whole fast flight takes about a second.
DRAIN_LIMIT_S = 10.0
INFINITE_QOS_S, INFINITE_QOS_NS = 2147483647, 4294967295  # rosbag2's "infinite" duration
PARAMETERS = {
    "output_dir": ParameterSpec(
        "the rosbag2 directory to create (required; it must not exist yet)", ""),
    "discovery_period_s": ParameterSpec(
        "how often new topics are looked for [s, wall time]", 0.2, 0.01, 60.0),
}


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


class RecorderNode(Node):
    """Thin adapter: the graph's topics (RawTopics) into one Recording."""

    def __init__(self) -> None:
        super().__init__("recorder_node")
        self.parameters = declare_parameters(self, PARAMETERS)
        output = Path(self.parameters["output_dir"])
        if not self.parameters["output_dir"] or output.exists():
            raise ValueError(f"output_dir '{output}' must be given and must not exist")
        self.recording = Recording(output, project_typestore())
        self.topics = RawTopics(self, self.parameters["discovery_period_s"], self.add_topic,
                                self.recording.write, purpose="recording")
        self.diagnostics = Diagnostics(self, silent_after_s=None,
                                       before_publish=self.report)

    def report(self) -> None:
        """Each topic's count of messages recorded so far, on /diagnostics (by topic name):
        what a run's starter waits for before it stops the recorder."""
        self.diagnostics.update(OK, f"recording {len(self.recording.counts)} topics",
                                dict(sorted(self.recording.counts.items())))

    def record_what_arrived(self) -> None:
        """After a stop signal: write the messages that have already arrived, then stop
        (a recorder behind a fast graph holds a backlog that a stop must not lose). Timers
        first go, so that a look that takes no message means none is left; at most
        DRAIN_LIMIT_S [s, wall time]."""
        for timer in list(self.timers):
            self.destroy_timer(timer)
        executor = SingleThreadedExecutor()
        executor.add_node(self)
        deadline = time.monotonic() + DRAIN_LIMIT_S
        try:
            while time.monotonic() < deadline:
                before = sum(self.recording.counts.values())
                executor.spin_once(timeout_sec=0.0)
                if sum(self.recording.counts.values()) == before:
                    break
        finally:
            executor.remove_node(self)
            executor.shutdown(timeout_sec=0.0)

    def add_topic(self, topic: str, message_type: str,
                  publishers: list[TopicEndpointInfo]) -> None:
        """A new topic of the recording, with its publishers' QoS profiles; ValueError for a
        type the recording cannot decode."""
        self.recording.add_topic(topic, message_type,
                                 [bag_qos(info.qos_profile) for info in publishers])

    def destroy_node(self) -> None:
        self.recording.close()
        counts = ", ".join(f"{topic} {count}" for topic, count in
                           sorted(self.recording.counts.items()))
        self.get_logger().info(f"recording closed in {self.recording.path}: {counts}")
        super().destroy_node()


def record(node: RecorderNode) -> None:
    """Spin until a stop signal, then record what had arrived by then."""
    spin(node)
    node.record_what_arrived()


def main(args: list[str] | None = None) -> int:
    return run_node("recorder_node", RecorderNode, run=record, args=args)


if __name__ == "__main__":
    sys.exit(main())
