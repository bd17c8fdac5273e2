"""Test setup: a ROS domain of each module's own, DDS on loopback only; the node tests'
scenario files and watching node."""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path

import cloudpickle
import helpers
import pytest
import yaml
from helpers.flight_cache import FlightCache
from helpers.flights import fly
from helpers.started_processes import started_processes
from uav_common.ros.graph_probe import RosGraph
from uav_common.ros_domain import DomainReservation, reserve_domain_id
from uav_fault_estimator.campaigns.campaign import Campaign, CampaignOptions
from uav_sim.scenario import Scenario, default_scenario_path, load_scenario
from uav_sim.simulation import Sample

REPO_ROOT = Path(__file__).resolve().parent.parent



def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The files whose slow tests allow the most time first (the sum of their timeouts, a
    rough forecast of their length), each file's tests together and in order: test.sh's
    workers take whole files in this order (--dist loadfile), so the long files start at
    once and the short ones fill in at the end, instead of a long file starting last on one
    worker while the other has nothing left."""
    weight: dict[Path, float] = {}
    for item in items:
        timeout = item.get_closest_marker("timeout")
        slow_s = float(timeout.args[0]) if timeout and item.get_closest_marker("slow") else 0.0
        weight[item.path] = weight.get(item.path, 0.0) + slow_s
    items.sort(key=lambda item: -weight[item.path])  # stable: files stay whole and in order

@pytest.fixture(scope="session", autouse=True)
def ros_logs(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Every ROS process of this test session keeps DDS on loopback and logs into the
    session's temporary folder rather than ~/.ros/log."""
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ["ROS_LOG_DIR"] = str(tmp_path_factory.mktemp("ros_log"))


@pytest.fixture(scope="session", autouse=True)
def user_configuration(tmp_path_factory: pytest.TempPathFactory) -> None:
    """The session's own user configuration folder (the campaigns' cache key), not the
    user's ~/.config."""
    os.environ["XDG_CONFIG_HOME"] = str(tmp_path_factory.mktemp("config"))


@pytest.fixture(scope="session")
def domain_reservations() -> Iterator[list[DomainReservation]]:
    """The reservation of the domain id in use (ros_domain), let go at the session's end."""
    reservations: list[DomainReservation] = []
    try:
        yield reservations
    finally:
        for reservation in reservations:
            reservation.close()


@pytest.fixture(scope="module", autouse=True)
def ros_domain(ros_logs: None, domain_reservations: list[DomainReservation]) -> int:
    """Each test module's ROS processes run on a domain id no other run holds and no
    earlier module of this session used last: an earlier module's endpoints (a killed
    node's may linger) are never seen by a later one. The new id is reserved before the
    previous one is let go, so the two differ (uav_common.ros_domain)."""
    domain_id, reservation = reserve_domain_id()
    for earlier in domain_reservations:
        earlier.close()
    domain_reservations[:] = [reservation]
    os.environ["ROS_DOMAIN_ID"] = str(domain_id)
    return domain_id


@pytest.fixture(scope="session")
def default_scenario() -> Scenario:
    """The shipped default scenario."""
    return load_scenario(default_scenario_path())


@pytest.fixture(scope="session")
def flight_cache(tmp_path_factory: pytest.TempPathFactory) -> FlightCache:
    """Flights flown once per run (helpers/flight_cache.py), in the run's own temporary
    folder: the one every xdist worker's folder is in, or this process's without xdist."""
    base = tmp_path_factory.getbasetemp()
    return FlightCache((base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base)
                       / "flights")


@pytest.fixture(scope="session")
def default_flight(default_scenario, flight_cache) -> list[Sample]:
    """The default scenario's samples, flown once per run."""
    return flight_cache.flown(fly, default_scenario)


@pytest.fixture(scope="session")
def campaign() -> Iterator[Campaign]:
    """Flights of the session's tests on local worker processes, started once (the
    calibrations' and studies' own execution layer): the cores shared among the pytest
    processes (test.sh's spread), at least two so that a campaign runs in parallel."""
    cloudpickle.register_pickle_by_value(helpers)  # not on the workers' path: sent along
    pytest_processes = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    workers = max(2, (os.cpu_count() or 1) // pytest_processes)
    with Campaign(CampaignOptions(workers=workers, progress=False)) as session_campaign:
        yield session_campaign


@pytest.fixture(scope="module")
def ros_graph(ros_domain: int) -> Iterator[RosGraph]:
    """A node in the test process for watching topics, on the module's domain (needs the
    built workspace)."""
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
    with started_processes(tmp_path) as start:
        yield start


@pytest.fixture
def short_scenario(tmp_path) -> Callable[..., Path]:
    """short_scenario(duration_s, base=None, **overrides): a scenario (base; None: the
    default) cut short, as a file."""

    def write(duration_s: float, base: Path | None = None, **overrides) -> Path:
        scenario = yaml.safe_load((base or default_scenario_path()).read_text())
        scenario.update(duration_s=duration_s, **overrides)
        path = tmp_path / f"short_{len(list(tmp_path.glob('short_*')))}.yaml"
        path.write_text(yaml.safe_dump(scenario))
        return path

    return write


@pytest.fixture
def graph(ros_graph):
    yield ros_graph
    ros_graph.unsubscribe_all()
