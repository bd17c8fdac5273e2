"""An rclpy node of its own inside a process (a test, a benchmark): topic discovery,
message collection and publishing, in a context of its own."""

from __future__ import annotations

import time
from typing import Any


class RosGraph:
    """A hidden node on the session's domain: topic discovery and message collection."""

    def __init__(self) -> None:
        import rclpy
        import rclpy.executors

        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(
            "_test_graph",
            context=self.context,
            start_parameter_services=False,
            enable_rosout=False,
        )
        self.executor = rclpy.executors.SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.subscriptions: dict[str, Any] = {}

    def topic_types(self) -> dict[str, list[str]]:
        return dict(self.node.get_topic_names_and_types())

    def wait_for_topics(self, topics: list[str], timeout_s: float) -> bool:
        """Whether every topic (absolute name) has appeared within timeout_s."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if set(topics) <= set(self.topic_types()):
                return True
            time.sleep(0.1)
        return False

    def subscribe(self, topics: dict[str, type], qos: Any = 10) -> dict[str, list[Any]]:
        """Start collecting every topic's messages into lists, filled while spin() runs."""
        received: dict[str, list[Any]] = {topic: [] for topic in topics}
        for topic, message_type in topics.items():
            self.subscriptions[topic] = self.node.create_subscription(
                message_type, topic, received[topic].append, qos)
        return received

    def wait_for_publishers(self, topic: str, count: int, timeout_s: float) -> bool:
        """Whether the subscription of topic (subscribe()) has been matched with at least
        count publishers within timeout_s: from then on nothing they publish is missed."""
        self.spin(timeout_s, until=lambda: self.subscriptions[topic].get_publisher_count()
                  >= count)
        return self.subscriptions[topic].get_publisher_count() >= count

    def wait_for_subscribers(self, topic: str, count: int, timeout_s: float) -> bool:
        """Whether the graph holds at least count subscriptions of topic (absolute name, this
        node's own included) within timeout_s: a recorder that subscribes once a topic has a
        publisher is in the graph before the first message is sent."""
        self.spin(timeout_s, until=lambda: self.node.count_subscribers(topic) >= count)
        return self.node.count_subscribers(topic) >= count

    def spin(self, duration_s: float, until: Any = None) -> None:
        """Process callbacks for duration_s, or until until() is true."""
        deadline = time.monotonic() + duration_s
        while time.monotonic() < deadline and not (until and until()):
            self.executor.spin_once(timeout_sec=0.05)

    def unsubscribe_all(self) -> None:
        for subscription in list(self.node.subscriptions):
            self.node.destroy_subscription(subscription)
        self.subscriptions.clear()

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self._rclpy.shutdown(context=self.context)
