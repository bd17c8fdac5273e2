"""An rclpy node inside the test process, to watch the graph and collect messages."""

from __future__ import annotations

import time
from typing import Any


class RosGraph:
    """A hidden node on the session's domain: topic discovery and message collection."""

    def __init__(self) -> None:
        import rclpy

        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(
            "_test_graph",
            context=self.context,
            start_parameter_services=False,
            enable_rosout=False,
        )

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

    def collect(
        self,
        topic: str,
        message_type: type,
        duration_s: float,
        qos: Any = 10,
        stop_after: int | None = None,
    ) -> list[Any]:
        """Messages received on topic for duration_s (or until stop_after of them)."""
        received: list[Any] = []
        subscription = self.node.create_subscription(message_type, topic, received.append, qos)
        deadline = time.monotonic() + duration_s
        try:
            while time.monotonic() < deadline and (
                stop_after is None or len(received) < stop_after
            ):
                self._rclpy.spin_once(self.node, timeout_sec=0.05)
        finally:
            self.node.destroy_subscription(subscription)
        return received

    def close(self) -> None:
        self.node.destroy_node()
        self._rclpy.shutdown(context=self.context)
