"""A run whose nodes live in a namespace (bringup.sh --ns /uav1) is recorded and reported
with `report.py --ns`; without it, report.py names the streams it lacks."""

from __future__ import annotations

import json
import signal
import subprocess
import sys

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from helpers.diagnostics import recorded_count
from helpers.repo import SCRIPTS
from uav_common.ros.qos import DIAGNOSTICS_QOS, STREAM_QOS
from uav_common.ros_processes import fast_flight_ros_args, ros2_run_argv, wait_until
from uav_fault_msgs.msg import FaultEstimate

pytestmark = pytest.mark.integration

REPORT = SCRIPTS / "report.py"
NAMESPACE = "/uav1"
DURATION_S = 20.0


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_a_namespaced_run_is_reported_with_its_namespace(short_scenario, start_process,
                                                         tmp_path, graph):
    estimates = graph.subscribe({f"{NAMESPACE}/faults/estimate": FaultEstimate}, STREAM_QOS)[
        f"{NAMESPACE}/faults/estimate"]
    diagnostics = graph.subscribe({"/diagnostics": DiagnosticArray}, DIAGNOSTICS_QOS)[
        "/diagnostics"]
    bag = tmp_path / "flight"
    recorder = start_process(ros2_run_argv("uav_fault_estimator", "recorder_node", ros_args=[
        "-p", f"output_dir:={bag}"]), "recorder_node")
    assert wait_until(lambda: bag.exists() or not recorder.running(), timeout_s=30)
    in_namespace = ["-r", f"__ns:={NAMESPACE}"]
    # each node subscribes to its inputs once its output has every subscription: this
    # test's and the recorder's estimates, mhe_node's and the recorder's residuals
    for name in ("mhe_node", "residual_node"):
        start_process(ros2_run_argv("uav_fault_estimator", name, ros_args=[
            *in_namespace, "-p", "wait_for_subscribers:=2"]), name)
    sim = start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=[
        *in_namespace, *fast_flight_ros_args(short_scenario(DURATION_S), subscribers=2)]),
        "sim_node")
    assert sim.wait(timeout_s=90) == 0, sim.output()
    expected = round(DURATION_S / 0.5)
    topic = f"{NAMESPACE}/faults/estimate"
    assert graph.wait(f"{expected} estimates here and in the recording", lambda: len(
        estimates) >= expected and recorded_count(diagnostics, topic) >= expected,
        timeout_s=30)
    assert recorder.stop(signal.SIGINT) == 0, recorder.output()

    out = tmp_path / "report"
    result = subprocess.run([sys.executable, str(REPORT), str(bag), "--out", str(out),
                             "--scenario", "short", "--ns", NAMESPACE],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["pipeline"]["messages_received"] == expected
    assert metrics["duration_s"] == pytest.approx(DURATION_S)

    bare = subprocess.run([sys.executable, str(REPORT), str(bag), "--out",
                           str(tmp_path / "bare")], capture_output=True, text=True, timeout=120)
    assert bare.returncode == 2 and "Traceback" not in bare.stderr
    assert bare.stderr.startswith(f"report.py: recording {bag}: no messages on "), bare.stderr
