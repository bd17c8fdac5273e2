"""The stream nodes' `qos` parameter: sensor_data (best effort) flies the graph without
acknowledgements, reliable stays the default, a name that is not a choice is refused in one
line, and pacing by acknowledgement (real_time_factor 0) is refused on best effort, at
start and when set live."""

from __future__ import annotations

import subprocess

import pytest
from rclpy.qos import ReliabilityPolicy, qos_profile_sensor_data
from uav_common.ros_processes import ros2_run_argv
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_msgs.msg import FaultAlarm, FaultEstimate, Residuals

pytestmark = pytest.mark.integration

SENSOR_DATA = ("-p", "qos:=sensor_data")
# a namespace of this test's own: earlier tests' nodes in the session's domain stay apart
NAMESPACE = ("-r", "__ns:=/qos")


def reliability(graph, topic: str) -> set[str]:
    """The reliability each publisher of topic offers."""
    return {info.qos_profile.reliability.name
            for info in graph.node.get_publishers_info_by_topic(topic)}


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_a_graph_on_sensor_data_estimates_and_the_default_stays_reliable(
        short_scenario, start_process, graph):
    received = graph.subscribe({"/qos/residuals": Residuals,
                                "/qos/faults/estimate": FaultEstimate,
                                "/qos/faults/alarm": FaultAlarm}, qos_profile_sensor_data)
    for name in ("residual_node", "mhe_node"):  # inputs once this test listens
        start_process(ros2_run_argv("uav_fault_estimator", name, ros_args=[
            *NAMESPACE, *SENSOR_DATA, "-p", "wait_for_subscribers:=1"]), name)
    # the detector on the default: reliable, so it hears no best-effort state
    start_process(ros2_run_argv("uav_fault_estimator", "detector_node",
                                ros_args=list(NAMESPACE)), "detector_node")
    assert graph.wait_for_subscribers("/qos/state", 2, timeout_s=30)
    duration_s, factor = 10.0, 5.0
    sim = start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=[
        *NAMESPACE, *SENSOR_DATA, "-p", f"scenario:={short_scenario(duration_s)}",
        "-p", f"real_time_factor:={factor}", "-p", "wait_for_subscribers:=1"]), "sim_node")
    graph.spin(30.0, until=lambda: len(received["/qos/faults/estimate"]) > 0)
    offered = {topic.removeprefix("/qos"): reliability(graph, topic) for topic in
               ("/qos/state", "/qos/residuals", "/qos/faults/estimate", "/qos/faults/alarm")}
    graph.spin(30.0, until=lambda: not sim.running())
    assert sim.wait(timeout_s=30) == 0, sim.output()
    updates = duration_s / ResidualSettings().update_period_s
    # the last ones may still be on their way (best effort: some may never come)
    graph.spin(5.0, until=lambda: len(received["/qos/residuals"]) >= updates
               and len(received["/qos/faults/estimate"]) >= updates)
    counts = {topic.removeprefix("/qos"): len(messages) for topic, messages in received.items()}
    print(f"offered reliability: {offered}; received: {counts}")
    assert offered == {"/state": {"BEST_EFFORT"}, "/residuals": {"BEST_EFFORT"},
                       "/faults/estimate": {"BEST_EFFORT"}, "/faults/alarm": {"RELIABLE"}}
    # one residual, and one estimate, per update period: at 5 times real time on loopback
    # next to nothing is lost, though nothing waits for acknowledgements
    assert counts["/residuals"] >= 0.9 * updates and counts["/faults/estimate"] >= 0.9 * updates
    assert counts["/faults/alarm"] == 0  # a reliable subscription does not match best effort


@pytest.mark.timeout(60)
def test_sensor_data_refuses_pacing_by_acknowledgement_and_an_unknown_choice():
    for ros_args, reason in (
            ([*SENSOR_DATA, "-p", "real_time_factor:=0.0"],
             "real_time_factor 0 (as fast as the subscribers acknowledge) needs qos reliable"),
            (["-p", "qos:=best_effort"],
             "parameter qos: 'best_effort' is not a choice; it must be one of reliable, "
             "sensor_data")):
        result = subprocess.run(ros2_run_argv("uav_sim", "sim_node", ros_args=ros_args),
                                capture_output=True, text=True, timeout=50)
        assert result.returncode == 2 and reason in result.stderr, result.stderr
        assert "Traceback" not in result.stderr


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_a_live_set_to_pacing_by_acknowledgement_is_refused_on_sensor_data(
        short_scenario, start_process):
    sim = start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=[
        *SENSOR_DATA, "-p", f"scenario:={short_scenario(600.0)}"]), "sim_node")
    result = subprocess.run(["ros2", "param", "set", "/sim_node", "real_time_factor", "0.0"],
                            capture_output=True, text=True, timeout=50)
    print(result.stdout, result.stderr)
    assert "Setting parameter failed: real_time_factor 0" in result.stdout + result.stderr
    assert sim.running()
    assert qos_profile_sensor_data.reliability == ReliabilityPolicy.BEST_EFFORT
