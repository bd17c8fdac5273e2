"""A hidden rclpy node inside a process that is not a node (a test, a benchmark, a tool):
topic discovery, message collection and publishing, in an rclpy context of its own, and
waits on a condition of the graph (a topic seen, endpoints matched) instead of a sleep."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Waited:
    """How a wait for a condition ended: true when the condition held in time. Its text
    says what was waited for, so that `assert graph.wait_for_...(...)` says it on failure."""

    met: bool
    what: str
    waited_s: float

    def __bool__(self) -> bool:
        return self.met

    def __repr__(self) -> str:
        verdict = "held" if self.met else "did NOT hold"
        return f"<waited {self.waited_s:.1f} s for {self.what}: {verdict}>"


class RosGraph:
    """A hidden node on the process's ROS domain: topic discovery and message collection."""

    def __init__(self) -> None:
        import rclpy
        import rclpy.executors

        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(
            "_graph_probe",
            context=self.context,
            start_parameter_services=False,
            enable_rosout=False,
        )
        self.executor = rclpy.executors.SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.subscriptions: dict[str, Any] = {}

    def topic_types(self) -> dict[str, list[str]]:
        return dict(self.node.get_topic_names_and_types())

    def wait(self, what: str, condition: Callable[[], bool], timeout_s: float) -> Waited:
        """Spin until condition() holds or timeout_s passes: a Waited, false (and saying what
        was waited for, and how long) when the deadline passed first."""
        started = time.monotonic()
        self.spin(timeout_s, until=condition)
        return Waited(bool(condition()), what, time.monotonic() - started)

    def wait_for_topics(self, topics: list[str], timeout_s: float) -> Waited:
        """Whether every topic (absolute name) has appeared within timeout_s."""
        return self.wait(f"topics {topics} in the graph",
                         lambda: set(topics) <= set(self.topic_types()), timeout_s)

    def subscribe(self, topics: dict[str, type], qos: Any = 10) -> dict[str, list[Any]]:
        """Start collecting every topic's messages into lists, filled while spin() runs."""
        received: dict[str, list[Any]] = {topic: [] for topic in topics}
        for topic, message_type in topics.items():
            self.subscriptions[topic] = self.node.create_subscription(
                message_type, topic, received[topic].append, qos)
        return received

    def wait_for_publishers(self, topic: str, count: int, timeout_s: float) -> Waited:
        """Whether the subscription of topic (subscribe()) has been matched with at least
        count publishers within timeout_s (on this side: a publisher may match it a moment
        later; a node's wait_for_subscribers waits on its own side)."""
        return self.wait(f"{count} publisher(s) matched with this test's {topic}",
                         lambda: self.subscriptions[topic].get_publisher_count() >= count,
                         timeout_s)

    def wait_for_subscribers(self, topic: str, count: int, timeout_s: float) -> Waited:
        """Whether the graph holds at least count subscriptions of topic (absolute name, this
        node's own included) within timeout_s, as this node sees the graph."""
        return self.wait(f"{count} subscription(s) of {topic} in the graph",
                         lambda: self.node.count_subscribers(topic) >= count, timeout_s)

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
