"""The main job's chain on a short flight: sim_node, residual_node, mhe_node and
recorder_node as processes, then metrics.json's figures from the recording alone, the vehicle
that flew (sim_node's /diagnostics), and the detector's calibration from it
(calibrate_detector.py --bags)."""

from __future__ import annotations

import signal
import subprocess
import sys

import numpy as np
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from helpers.diagnostics import recorded_count
from helpers.repo import SCRIPTS
from uav_common.channels import PAPER_FAULT_NAMES
from uav_common.ros.qos import DIAGNOSTICS_QOS, STREAM_QOS
from uav_common.ros_processes import fast_flight_ros_args, ros2_run_argv, wait_until
from uav_fault_estimator.chain.offline import fly_on_grid
from uav_fault_estimator.detection.calibration_file import calibration_from_dict
from uav_fault_estimator.recording.project_bag import (
    flight_from_recording,
    project_typestore,
    read_topics,
    recorded_vehicle,
)
from uav_fault_estimator.reporting import figures, report
from uav_fault_msgs.msg import FaultEstimate
from uav_sim.scenario import load_scenario

pytestmark = pytest.mark.integration

CALIBRATE = SCRIPTS / "calibrate_detector.py"
DURATION_S = 60.0
CALM = {"north_mps": 4.0, "east_mps": 3.0, "down_mps": 0.0, "turbulence": "none",
        "filter_time_constant_s": 10}
LIFT_LOSS = {"name": "left_wing_lift_loss", "start_s": 15, "ramp_s": 0, "magnitude_pct": 10}


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_a_recorded_flight_gives_its_metrics(short_scenario, start_process, tmp_path, graph):
    estimates = graph.subscribe({"/faults/estimate": FaultEstimate}, STREAM_QOS)[
        "/faults/estimate"]
    diagnostics = graph.subscribe({"/diagnostics": DiagnosticArray}, DIAGNOSTICS_QOS)[
        "/diagnostics"]
    bag = tmp_path / "flight"
    recorder = start_process(ros2_run_argv("uav_fault_estimator", "recorder_node", ros_args=[
        "-p", f"output_dir:={bag}"]), "recorder_node")
    assert wait_until(lambda: bag.exists() or not recorder.running(), timeout_s=30)
    # each node subscribes to its inputs once its output has every subscription: this
    # test's and the recorder's estimates, mhe_node's and the recorder's residuals
    start_process(ros2_run_argv("uav_fault_estimator", "mhe_node", ros_args=[
        "-p", "wait_for_subscribers:=2"]), "mhe_node")
    start_process(ros2_run_argv("uav_fault_estimator", "residual_node", ros_args=[
        "-p", "wait_for_subscribers:=2"]), "residual_node")
    scenario = short_scenario(DURATION_S, wind=CALM, faults=[LIFT_LOSS])
    sim = start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=fast_flight_ros_args(
        scenario, subscribers=2)), "sim_node")  # residual_node and the recorder
    assert sim.wait(timeout_s=90) == 0, sim.output()
    expected = round(DURATION_S / 0.5)
    typestore = project_typestore()

    # the last estimates may still be on their way when the simulator ends
    assert graph.wait(f"{expected} estimates here and in the recording", lambda: len(
        estimates) >= expected and recorded_count(diagnostics, "/faults/estimate") >= expected,
        timeout_s=30)
    assert recorder.stop(signal.SIGINT) == 0, recorder.output()

    messages = read_topics(bag, typestore, (*report.TOPICS, *figures.TOPICS))
    metrics = report.run_metrics(report.run_from(messages, bag), scenario="short")
    written = figures.plot_run(messages, tmp_path / "figures")
    print(metrics)
    print("figures:", [(path.name, path.stat().st_size) for path in written])
    assert [path.name for path in written] == [
        "states.png", "track.png", "wind.png", "residuals.png", "sensitivity.png",
        "estimates.png"]
    assert all(path.stat().st_size > 10_000 for path in written)
    assert metrics["pipeline"]["messages_received"] == expected
    assert metrics["duration_s"] == pytest.approx(DURATION_S)
    assert list(metrics["faults"]) == list(PAPER_FAULT_NAMES)
    lift = metrics["faults"]["left_wing_lift_loss"]
    assert lift["seeded"] and lift["seeded_final_pct"] == 10.0
    assert lift["estimate_final_pct"] == pytest.approx(10.0, abs=1.0)  # 45 s after the step
    assert lift["detection_delay_s"] is not None and lift["detection_delay_s"] <= 10.0
    assert metrics["false_alarms"] == [] and metrics["solver"]["failures"] == 0
    assert recorded_vehicle(bag, typestore) == "aerosonde"  # the scenario's

    # the detector's calibration from the recording: the same flight as the core flies it
    recorded = flight_from_recording(bag, typestore, 0.2)
    flown = fly_on_grid(load_scenario(scenario), 0.2).detector_flight
    for name, got, expected in zip(recorded._fields, recorded, flown, strict=True):
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9,  # stamps: ns to s
                                   equal_nan=True, err_msg=name)
    assert np.isfinite(recorded.setpoints[1:, :2]).all()  # the autopilot's roll and pitch
    calibration = tmp_path / "calibration.yaml"
    result = subprocess.run([sys.executable, str(CALIBRATE), "--bags", str(bag), "--out",
                             str(calibration)], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert str(bag) in calibration.read_text().splitlines()[0]
    assert calibration_from_dict(yaml.safe_load(calibration.read_text())).window == 25
