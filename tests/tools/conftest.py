"""Live processes the `ros2` command's tests query: a node with parameters and services, and
a publisher of every message type."""

from __future__ import annotations

import sys

import pytest
from helpers.samples import SAMPLE_FIELDS, topic_of
from uav_common.ros_processes import RosProcess, ros2_run_argv

PUBLISHER = [sys.executable, "tests/helpers/sample_publisher.py"]
SAMPLE_TOPICS = ["/" + topic_of(name) for name in SAMPLE_FIELDS]


@pytest.fixture
def mhe_node(start_process, ros_graph) -> RosProcess:
    """mhe_node, waiting for residuals: a node with the project's parameters."""
    process = start_process(ros2_run_argv("uav_fault_estimator", "mhe_node"), "mhe_node")
    assert ros_graph.wait_for_topics(["/faults/estimate"], timeout_s=30), process.output()
    return process


@pytest.fixture
def sample_publisher(start_process, ros_graph) -> RosProcess:
    """A process publishing one sample of every message type at 10 Hz."""
    process = start_process(PUBLISHER, "sample_publisher")
    assert ros_graph.wait_for_topics(SAMPLE_TOPICS, timeout_s=30), process.output()
    return process
