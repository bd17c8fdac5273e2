"""Session-wide test setup: a ROS domain of the run's own, DDS on loopback only."""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest
from ros_graph import RosGraph
from ros_processes import RosProcess, reserve_domain_id

REPO_ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session", autouse=True)
def ros_domain(tmp_path_factory: pytest.TempPathFactory) -> Iterator[int]:
    """Every ROS process of this test session runs on a domain id no other run holds,
    and logs into the session's temporary folder rather than ~/.ros/log."""
    domain_id, lock = reserve_domain_id()
    os.environ["ROS_DOMAIN_ID"] = str(domain_id)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ["ROS_LOG_DIR"] = str(tmp_path_factory.mktemp("ros_log"))
    try:
        yield domain_id
    finally:
        lock.close()


@pytest.fixture(scope="session")
def ros_graph(ros_domain: int) -> Iterator[RosGraph]:
    """A node in the test process for watching topics (needs the built workspace)."""
    if shutil.which("ros2") is None:
        pytest.fail("ros2 is not on PATH: run the tests through scripts/test.sh")
    graph = RosGraph()
    try:
        yield graph
    finally:
        graph.close()


@pytest.fixture
def start_process(tmp_path: Path) -> Iterator:
    """start_process(argv, name) starts a command as a process; all are stopped at teardown."""
    started: list[RosProcess] = []

    def start(argv: list[str], name: str) -> RosProcess:
        process = RosProcess(argv, tmp_path / f"{name}.log")
        started.append(process)
        return process

    try:
        yield start
    finally:
        for process in reversed(started):
            process.stop()
