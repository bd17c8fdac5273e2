"""The aileron loss read back from a PX4 ULog and from a MAVROS ROS 1 bag (PWM outputs at
2.9 Hz, rates at 10 Hz, at their own instants, FLU in the bag) is found by the detector as
soon as in the direct run of the same flight on the detector's grid: within one sample."""

from __future__ import annotations

import dataclasses

import pytest
from helpers import simulated_logs
from uav_aircraft.airframe import load_airframe
from uav_fault_estimator.detection.calibration import DEFAULT_SAMPLE_PERIOD_S
from uav_fault_estimator.detection.calibration_file import (
    read_calibration,
    surface_calibration_path,
)
from uav_fault_estimator.detection.detector import run_detector
from uav_fault_estimator.detection.detector_settings import DetectorSettings
from uav_fault_estimator.flight_logs.readers import read_log
from uav_fault_estimator.flight_logs.resample import detector_samples
from uav_fault_estimator.flight_logs.screening import first_combined_alarm_s
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import load_scenario

ONSET_S = 60.0
SEED = 17


@pytest.mark.timeout(120)
def test_the_logs_give_the_direct_runs_detection_delay(tmp_path):
    aileron = load_scenario(scenarios_dir() / "aileron_loss.yaml")
    scenario = dataclasses.replace(aileron, duration_s=100.0, faults=tuple(
        dataclasses.replace(fault, start_s=ONSET_S) for fault in aileron.faults))
    truth = simulated_logs.simulate_truth(scenario, SEED)
    simulated_logs.write_ulog(tmp_path / "flight.ulg", truth)
    simulated_logs.write_mavros_bag(tmp_path / "flight.bag", truth, SEED)
    calibration = read_calibration(str(surface_calibration_path()))  # no setpoints in the logs
    airframe = load_airframe(simulated_logs.FIXTURE_AIRFRAME)
    p_fa = DetectorSettings().false_alarm_probability
    delays = {"direct": first_combined_alarm_s(
        run_detector(calibration, truth.grid, p_fa), ONSET_S)}
    for name in ("flight.ulg", "flight.bag"):
        inputs = detector_samples(read_log(tmp_path / name), airframe, DEFAULT_SAMPLE_PERIOD_S)
        delays[name] = first_combined_alarm_s(
            run_detector(calibration, inputs.flight, p_fa), ONSET_S)
    print("first combined alarm after the onset [s]:", delays)
    assert delays["direct"] is not None and delays["direct"] - ONSET_S <= 10.0
    for name in ("flight.ulg", "flight.bag"):
        assert delays[name] == pytest.approx(delays["direct"], abs=DEFAULT_SAMPLE_PERIOD_S + 1e-9)
