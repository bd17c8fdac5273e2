"""scripts/bringup.sh: the nodes live under a namespace, and Ctrl-C on the script alone
stops every one of them; two aircraft in one domain, ending when both have landed."""

from __future__ import annotations

import os
import signal
import subprocess

import pytest
from helpers.process_table import NODE_NAMES, kill_all, processes
from helpers.repo import SCRIPTS
from nav_msgs.msg import Odometry
from tf2_msgs.msg import TFMessage
from uav_common.message_fields import stamp_seconds
from uav_common.ros.qos import STREAM_QOS
from uav_common.ros_processes import wait_until
from uav_fault_msgs.msg import FaultEstimate

pytestmark = pytest.mark.integration

BRINGUP = SCRIPTS / "bringup.sh"


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_bringup_runs_the_nodes_and_ctrl_c_stops_them_all(
        start_process, short_scenario, graph, ros_domain, tmp_path) -> None:
    logs = tmp_path / "logs"

    def leftovers() -> list:
        return processes(lambda info: str(logs) in info.cmdline or (
            any(name in info.cmdline for name in NODE_NAMES)
            and info.environ.get("ROS_DOMAIN_ID") == str(ros_domain)))

    estimates = graph.subscribe({"/uav2/faults/estimate": FaultEstimate}, STREAM_QOS)[
        "/uav2/faults/estimate"]
    bringup = start_process([str(BRINGUP), "--ns", "/uav2", "--scenario",
                             str(short_scenario(60.0)), "--logs", str(logs)], "bringup")
    try:
        graph.spin(60.0, until=lambda: len(estimates) >= 2 or not bringup.running())
        assert len(estimates) >= 2, bringup.output()
        assert estimates[-1].names == list(estimates[0].names)
        output = bringup.output()
        assert str(logs) in output and "ros2 topic echo /uav2/faults/estimate" in output
        # each node's output once: no rcl log file beside it
        assert {path.name for path in logs.iterdir()} == {
            "sim_node.log", "residual_node.log", "mhe_node.log", "detector_node.log",
            "standard_topics_node.log"}

        os.kill(bringup.pid, signal.SIGINT)  # the script only, not its group
        assert bringup.wait(15) == 130, bringup.output()
        assert wait_until(lambda: not leftovers(), timeout_s=1.0), leftovers()
        print(bringup.output())
    finally:
        kill_all(leftovers())


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_two_aircraft_fly_on_one_clock_and_the_run_ends_when_both_have(
        start_process, short_scenario, graph, tmp_path) -> None:
    logs = tmp_path / "logs"
    topics = {f"/uav{k}/faults/estimate": FaultEstimate for k in (1, 2)}
    estimates = graph.subscribe(topics, STREAM_QOS)
    transforms = graph.subscribe({"/tf": TFMessage}, STREAM_QOS)["/tf"]
    odometry = graph.subscribe({f"/uav{k}/odom": Odometry for k in (1, 2)}, STREAM_QOS)
    # the leading simulator at 10 times real time; each simulator starts once its vehicle's
    # residual_node, detector_node and standard_topics_node take its state, the last once
    # this test takes its odom (a live bringup does not wait: the first samples of a 1 s
    # flight would go to discovery)
    fast = tmp_path / "fast.yaml"
    fast.write_text("/**/sim_node:\n  ros__parameters:\n    real_time_factor: 10.0\n"
                    "    wait_for_subscribers: 3\n"
                    "/**/standard_topics_node:\n  ros__parameters:\n"
                    "    wait_for_subscribers: 1\n")
    scenarios = [str(short_scenario(10.0)), str(short_scenario(10.0, faults=[]))]
    bringup = start_process([str(BRINGUP), "--scenario", scenarios[0], "--scenario",
                             scenarios[1], "--params", str(fast), "--logs", str(logs)],
                            "bringup")
    assert bringup.wait(60) == 0, bringup.output()
    assert graph.wait("the estimates at 10 s of both aircraft", lambda: all(  # may be on
        received and stamp_seconds(received[-1].header.stamp) >= 10.0  # their way still
        for received in estimates.values()), timeout_s=30)
    output = bringup.output()
    print(output)
    assert "every sim_node finished its scenario" in output
    # the first estimates may go to discovery at ten times real time (on a busy machine
    # up to 7 of 20 did), never the second half of the flight nor the end: every estimate
    # from 5 s to 10 s, each half second
    stamps = [[stamp_seconds(m.header.stamp) for m in received] for received in estimates.values()]
    print("estimates received:", [len(s) for s in stamps], "stamps:", stamps)
    second_half = [5.0 + 0.5 * k for k in range(11)]
    assert all(set(second_half) <= set(mine) and mine[-1] == 10.0 for mine in stamps)
    # both aircraft in the one map, each its own base_link
    assert graph.wait("/tf of both aircraft", lambda: len(
        {t.child_frame_id for m in transforms for t in m.transforms}) == 2, timeout_s=10)
    assert {(t.header.frame_id, t.child_frame_id) for m in transforms for t in m.transforms} \
        == {("map", "uav1/base_link"), ("map", "uav2/base_link")}
    assert [{m.child_frame_id for m in odometry[f"/uav{k}/odom"]} for k in (1, 2)] == [
        {"uav1/base_link"}, {"uav2/base_link"}]
    assert {str(path.relative_to(logs)) for path in logs.rglob("*") if path.is_file()} == {
        f"uav{k}/{name}.log" for k in (1, 2)
        for name in ("sim_node", "residual_node", "mhe_node", "detector_node",
                     "standard_topics_node")}
    assert "following /clock" in (logs / "uav2/sim_node.log").read_text()
    assert "real-time factor 10" in (logs / "uav1/sim_node.log").read_text()
    refused = start_process([str(BRINGUP), "--ns", "/a", "--scenario", scenarios[0],
                             "--scenario", scenarios[1]], "refused")
    assert refused.wait(10) == 2
    assert "--ns names the namespace of one aircraft" in refused.output()


@pytest.mark.timeout(120)
def test_a_model_calibration_that_cannot_be_used_ends_bringup_before_any_node(tmp_path):
    """One line naming the file, status 2, and no node started (no log folder filled)."""
    calibration = tmp_path / "model.yaml"
    calibration.write_text("vehicle: aerosonde\nmodel_file: aerosonde.xml\nmodel_sha256: '0'\n"
                           "aircraft: {}\n")
    logs = tmp_path / "logs"
    result = subprocess.run([str(BRINGUP), "--model-calibration", str(calibration), "--logs",
                             str(logs)], capture_output=True, text=True, timeout=100)
    assert result.returncode == 2, result
    lines = [line for line in result.stderr.splitlines() if line.startswith("bringup.sh:")]
    assert len(lines) == 1 and "made for another model file" in lines[0], result.stderr
    assert not logs.exists() or not any(logs.iterdir())
