"""Every topic of the graph, subscribed raw (serialized CDR, never decoded) once it has
publishers: what recorder_node and foxglove_node share.

Each topic is subscribed with the reliability its publishers offer and keep-all history, so
that a fast simulation loses nothing while the node catches up; a subscription that asks
for more than a publisher offers would not match it. Messages are handed on with their
receive time on the node's clock: simulation time with use_sim_time, wall time otherwise.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.topic_endpoint_info import TopicEndpointInfo

# accept(topic, type name "pkg/msg/Name", its publishers): takes the topic on, or raises
# ValueError saying why not
Accept = Callable[[str, str, list[TopicEndpointInfo]], None]
# receive(topic, receive time [ns, node clock], serialized message)
Receive = Callable[[str, int, bytes], None]


def message_class(type_name: str) -> type:
    """The Python class of a ROS type name such as `std_msgs/msg/Header`; ValueError when
    no installed package defines it."""
    package, _, name = type_name.partition("/msg/")
    try:
        return getattr(importlib.import_module(f"{package}.msg"), name)
    except (ImportError, AttributeError):
        raise ValueError(f"no Python message class for {type_name}") from None


def subscription_qos(publishers: list[TopicEndpointInfo]) -> QoSProfile:
    """Keep-all and volatile; reliable when every publisher is, else best effort (a reliable
    subscription does not match a best-effort publisher)."""
    reliable = all(info.qos_profile.reliability == ReliabilityPolicy.RELIABLE
                   for info in publishers)
    return QoSProfile(
        history=HistoryPolicy.KEEP_ALL,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.VOLATILE,
    )


class RawTopics:
    """Looks for new topics every period_s of wall time (the node's clock stands still under
    use_sim_time until /clock runs) and subscribes to each one, raw, once it has publishers
    and accept() takes it; a topic refused is said once (why, with `purpose`) and left."""

    def __init__(self, node: Node, period_s: float, accept: Accept, receive: Receive,
                 purpose: str) -> None:
        self._node = node
        self._accept = accept
        self._receive = receive
        self._purpose = purpose
        self.subscribed: set[str] = set()
        self._refused: set[str] = set()
        node.create_timer(period_s, self.discover, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.discover()

    def discover(self) -> None:
        """Subscribe to every topic seen for the first time with publishers."""
        for topic, types in self._node.get_topic_names_and_types():
            if topic in self.subscribed or topic in self._refused or not types:
                continue
            publishers = self._node.get_publishers_info_by_topic(topic)
            if not publishers:  # only subscribed to (e.g. /clock, by our own sim time) so far:
                continue        # nothing to take yet; its QoS comes with its publishers
            try:
                message_type = message_class(types[0])
                self._accept(topic, types[0], publishers)
            except ValueError as error:
                self._refused.add(topic)
                self._node.get_logger().warning(f"not {self._purpose} {topic}: {error}")
                continue
            self.subscribed.add(topic)
            self._node.create_subscription(
                message_type, topic,
                lambda data, topic=topic: self._receive(
                    topic, self._node.get_clock().now().nanoseconds, data),
                subscription_qos(publishers), raw=True,
            )
