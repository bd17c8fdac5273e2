"""Publishes every sample message at 10 Hz until interrupted (a test fixture process)."""

import sys
from pathlib import Path

import rclpy
from rclpy.executors import ExternalShutdownException

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from helpers.samples import SAMPLE_FIELDS, build_sample, topic_of

PERIOD_S = 0.1


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("sample_publisher")
    samples = [
        (node.create_publisher(type(message), topic_of(name), 10), message)
        for name in SAMPLE_FIELDS
        for message in [build_sample(name)]
    ]

    def publish_all() -> None:
        for publisher, message in samples:
            publisher.publish(message)

    node.create_timer(PERIOD_S, publish_all)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
