"""Publishes every sample message at 10 Hz until interrupted (a test fixture process)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from helpers.fixture_node import run_timer_node
from helpers.samples import SAMPLE_FIELDS, build_sample, topic_of

PERIOD_S = 0.1


def publishers(node):
    """Every sample message with its publisher: the tick publishes them all."""
    samples = [(node.create_publisher(type(message), topic_of(name), 10), message)
               for name in SAMPLE_FIELDS for message in [build_sample(name)]]

    def publish_all() -> None:
        for publisher, message in samples:
            publisher.publish(message)

    return publish_all


def main() -> None:
    run_timer_node("sample_publisher", PERIOD_S, publishers)


if __name__ == "__main__":
    main()
