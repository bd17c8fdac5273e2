"""detector_node as a process beside sim_node: an alarm message on every 0.2 s sample
with the calibration's thresholds, the same alarms the core makes offline with the window
and forgetting factor the calibration carries, and a calibration of another airframe
refused with one line."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest
import yaml
from helpers.alarms import assert_alarms_are_the_cores
from uav_common.message_fields import stamp_seconds
from uav_common.ros.qos import STREAM_QOS
from uav_common.ros_processes import fast_flight_ros_args, ros2_run_argv
from uav_fault_estimator.chain.offline import fly_on_grid
from uav_fault_estimator.detection.calibration_file import calibration_to_dict
from uav_fault_estimator.detection.calibration_fit import calibrate
from uav_fault_estimator.detection.detector import SelfTuningDetector, run_detector
from uav_fault_estimator.detection.generators import SURFACE_GENERATORS
from uav_fault_msgs.msg import FaultAlarm
from uav_sim.scenario import load_scenario

pytestmark = pytest.mark.integration

GENERATORS = (*SURFACE_GENERATORS, "propulsion")

DURATION_S = 60.0  # the RLS settles after 30 s: half of the flight is tested


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_alarms_on_every_sample_as_the_core_makes_them(short_scenario, graph, start_process,
                                                        tmp_path):
    """With a calibration of four generators (the paper's three and propulsion), made from
    the flight itself with a window and forgetting factor of its own (not the defaults):
    the node's channels are the calibration's, its numbers the core's."""
    scenario = short_scenario(DURATION_S)
    flight = fly_on_grid(load_scenario(scenario), 0.2)[:3]
    calibration = calibrate([flight], forgetting_factor=0.99, window=40, generators=GENERATORS)
    calibration_file = tmp_path / "calibration.yaml"
    calibration_file.write_text(yaml.safe_dump(calibration_to_dict(calibration), sort_keys=False))
    alarms = graph.subscribe({"/faults/alarm": FaultAlarm}, STREAM_QOS)["/faults/alarm"]
    start_process(ros2_run_argv("uav_fault_estimator", "detector_node", ros_args=[
        "-p", f"calibration_file:={calibration_file}",
        "-p", "wait_for_subscribers:=1"]), "detector_node")  # inputs once this test listens
    sim = start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=fast_flight_ros_args(
        scenario, subscribers=1)), "sim_node")
    assert sim.wait(timeout_s=90) == 0, sim.output()
    expected = round(DURATION_S / 0.2)  # every grid sample but the first (no r[k-1] yet)
    graph.spin(30.0, until=lambda: len(alarms) >= expected)

    stamps = np.array([stamp_seconds(m.header.stamp) for m in alarms])
    np.testing.assert_allclose(stamps, 0.2 * np.arange(1, expected + 1), atol=1e-9)
    assert {tuple(m.channel_names) for m in alarms} == {GENERATORS}
    # the same numbers as the core's offline run of the same flight
    assert_alarms_are_the_cores(alarms, run_detector(calibration, flight, 0.01))
    detector = SelfTuningDetector(calibration, 0.01)
    np.testing.assert_allclose(alarms[-1].threshold, detector.thresholds, rtol=1e-12)
    settled = [m for m in alarms if np.isfinite(m.statistic).all()]
    print(f"{len(alarms)} alarm messages, {len(settled)} with every test running; "
          f"GLRT alarms {np.sum([m.alarm for m in settled], axis=0)}, parameter alarms "
          f"{sum(m.parameter_alarm for m in settled)}, combined "
          f"{sum(m.combined_alarm for m in settled)}")
    assert len(settled) == round((DURATION_S - 30.0) / 0.2) + 1  # from 30 s on, both ends


@pytest.mark.timeout(60)
def test_a_calibration_of_another_airframe_is_refused_with_one_line():
    result = subprocess.run(
        ros2_run_argv("uav_fault_estimator", "detector_node",
                      ros_args=["-p", "airframe:=carbon_z_alfa"]),
        capture_output=True, text=True, timeout=50)
    assert result.returncode == 2, result  # bad input
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr
    assert "is for the airframe 'aerosonde_sim', not 'carbon_z_alfa'" in lines[0], lines
