"""Live processes the `ros2` command's tests query: a node with parameters and services, and
a publisher of every message type. Both are started once per test module and shared by its
tests: they only read them (or put back what they change), and each start costs a process
start-up and discovery (2-4 s on a loaded machine)."""

from __future__ import annotations

import sys
from collections.abc import Iterator

import pytest
from helpers.samples import SAMPLE_FIELDS, topic_of
from helpers.started_processes import StartProcess, started_processes
from uav_common.ros_processes import RosProcess, ros2_run_argv

PUBLISHER = [sys.executable, "tests/helpers/sample_publisher.py"]
SAMPLE_TOPICS = ["/" + topic_of(name) for name in SAMPLE_FIELDS]


@pytest.fixture(scope="module")
def start_module_process(tmp_path_factory: pytest.TempPathFactory,
                         ros_domain: int) -> Iterator[StartProcess]:
    """start_process for the module's shared processes: stopped when the module's tests end."""
    with started_processes(tmp_path_factory.mktemp("module_processes")) as start:
        yield start


@pytest.fixture(scope="module")
def mhe_node(start_module_process, ros_graph) -> RosProcess:
    """mhe_node, waiting for residuals: a node with the project's parameters."""
    process = start_module_process(ros2_run_argv("uav_fault_estimator", "mhe_node"), "mhe_node")
    assert ros_graph.wait_for_topics(["/faults/estimate"], timeout_s=30), process.output()
    return process


@pytest.fixture(scope="module")
def sample_publisher(start_module_process, ros_graph) -> RosProcess:
    """A process publishing one sample of every message type at 10 Hz."""
    process = start_module_process(PUBLISHER, "sample_publisher")
    assert ros_graph.wait_for_topics(SAMPLE_TOPICS, timeout_s=30), process.output()
    return process


@pytest.fixture(autouse=True)
def shared_processes_alive(request: pytest.FixtureRequest) -> None:
    """Fail at once, rather than with puzzling outputs, if a shared process this test uses
    has died (e.g. killed by an earlier test's teardown)."""
    for name in ("mhe_node", "sample_publisher"):
        if name in request.fixturenames:
            process: RosProcess = request.getfixturevalue(name)
            assert process.running(), process.output()
