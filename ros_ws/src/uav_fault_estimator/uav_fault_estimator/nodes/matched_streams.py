"""Subscriptions whose messages are matched by stamp (stamp_matching.py) for a node: the
ROS side shared by residual_node and detector_node."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rclpy.node import Node
from uav_sim.ros.messages import stamp_nanoseconds
from uav_sim.ros.node_tools import STREAM_QOS

from uav_fault_estimator.nodes.stamp_matching import StampMatcher

# (message type, message -> array) per topic
Streams = dict[str, tuple[type, Callable[[Any], Any]]]


class MatchedStreams:
    """Subscribes each topic (reliable, keep-all) in the order given: sim_node's
    wait_for_subscribers counts `state` subscriptions, so list `state` last. Complete sets
    go to on_sample(time_s, arrays by topic) in stamp order, with the optional topics'
    arrays where they came (waited for while the topic has a publisher, for up to
    StampMatcher.optional_wait newer sets); a required stamp not newer than the
    last processed one (a restarted source) is warned of once (ending with restart_note:
    what on_restart does), resets the matcher and calls on_restart() first."""

    def __init__(self, node: Node, streams: Streams,
                 on_sample: Callable[[float, dict[str, Any]], None],
                 on_restart: Callable[[], None], restart_note: str,
                 optional: Streams | None = None) -> None:
        self.node = node
        optional = optional or {}
        self.to_array = {topic: convert for topic, (_, convert)
                         in {**optional, **streams}.items()}
        self.matcher = StampMatcher(tuple(streams), tuple(optional), self.has_publisher)
        self.on_sample, self.on_restart = on_sample, on_restart
        self.restart_note = restart_note
        self.restarts = 0
        for topic, (message_type, _) in {**optional, **streams}.items():
            node.create_subscription(
                message_type, topic, lambda message, topic=topic: self.receive(topic, message),
                STREAM_QOS)

    def has_publisher(self, topic: str) -> bool:
        """Whether some node publishes this topic now."""
        return self.node.count_publishers(topic) > 0

    @property
    def dropped_sets(self) -> int:
        """Stamps dropped because some stream's message never came."""
        return self.matcher.dropped_sets

    def receive(self, topic: str, message: Any) -> None:
        stamp_ns = stamp_nanoseconds(message.header.stamp)
        if topic in self.matcher.streams and self.matcher.is_backwards(stamp_ns):
            self.node.get_logger().warning(
                f"{topic} stamp {stamp_ns / 1e9:.3f} s is not newer than the last processed one:"
                f" the source restarted, {self.restart_note}")
            self.matcher.reset()
            self.restarts += 1
            self.on_restart()
        for sample_ns, payloads in self.matcher.add(topic, stamp_ns,
                                                    self.to_array[topic](message)):
            self.on_sample(sample_ns / 1e9, payloads)
