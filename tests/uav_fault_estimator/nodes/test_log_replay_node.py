"""log_replay_node as a process: a simulated aileron-fault flight written as a PX4 ULog, and as
a ROS 1 MAVROS bag (PWM outputs at 2.9 Hz, rates at 10 Hz, jittered; FLU in the bag)
exported as an ALFA flight folder with the autopilot's setpoints, replayed as fast as
detector_node keeps up, gives the alarms the core's offline run of the same log gives; a
bad log or airframe is one line and status 2."""

from __future__ import annotations

import dataclasses
import subprocess
from pathlib import Path

import numpy as np
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from helpers import simulated_logs
from helpers.alarms import assert_alarms_are_the_cores
from helpers.simulated_logs import ALFA, FIXTURE_AIRFRAME
from uav_aircraft.airframe import load_airframe
from uav_common.message_fields import air_data_array, setpoints_array, stamp_seconds
from uav_common.ros.qos import DIAGNOSTICS_QOS, STREAM_QOS
from uav_common.ros_processes import ros2_run_argv
from uav_fault_estimator.detection.calibration_file import (
    calibration_to_dict,
    read_calibration,
    surface_calibration_path,
)
from uav_fault_estimator.detection.calibration_fit import calibrate
from uav_fault_estimator.detection.detector import DetectorFlight, run_detector
from uav_fault_estimator.flight_logs.readers import read_log
from uav_fault_estimator.flight_logs.resample import detector_samples
from uav_fault_estimator.flight_logs.streams import ATTITUDE, GROUND_VELOCITY
from uav_fault_msgs.msg import AircraftState, AirData, AutopilotSetpoints, FaultAlarm
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import load_scenario

pytestmark = pytest.mark.integration

DURATION_S = 60.0  # the detector settles after 30 s
FAULT_START_S = 40.0  # the aileron loss, moved from 150 s into the flight
SEED = 17
ALFA_FLIGHT = "carbonZ_2018-01-01-00-00-00_aileron_fault"  # ALFA's folder naming
# the paper's generators and those the ALFA benchmark runs
TRACKING_SET = ("roll", "pitch", "yaw", "roll_tracking", "pitch_tracking", "climb_tracking",
                "lateral_force")


@pytest.fixture(scope="module")
def aileron_fault_logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, float]]:
    """The aileron-loss scenario, cut to DURATION_S with its fault at FAULT_START_S, as a
    PX4 ULog and a MAVROS bag with the fixture airframe's PWM outputs (about 1 s): by
    suffix, the file and its first log time [s of simulation time]."""
    scenario = load_scenario(scenarios_dir() / "aileron_loss.yaml")
    (fault,) = scenario.faults
    scenario = dataclasses.replace(scenario, duration_s=DURATION_S, faults=(
        dataclasses.replace(fault, start_s=FAULT_START_S),))
    truth = simulated_logs.simulate_truth(scenario, SEED)
    folder = tmp_path_factory.mktemp("replay")
    simulated_logs.write_ulog(folder / "aileron_fault.ulg", truth)
    bag_start_s = simulated_logs.write_mavros_bag(folder / "aileron_fault.bag", truth, SEED)
    alfa = folder / ALFA_FLIGHT
    simulated_logs.export_csv(folder / "aileron_fault.bag", alfa, ALFA)
    write_nav_info(alfa)
    return {"ulg": (folder / "aileron_fault.ulg", 0.0),
            "bag": (folder / "aileron_fault.bag", bag_start_s),
            "alfa": (alfa, bag_start_s)}


def write_nav_info(folder: Path) -> None:
    """ALFA's nav_info/roll, /pitch and /velocity for an ALFA flight folder: the measured
    values the log's attitude [deg] and ground velocity (NED) [m/s], the commanded ones those
    plus a slow swing (an autopilot's setpoint leads its aircraft), at their instants in the
    log's clock."""
    log = read_log(folder)
    attitude, velocity = log.streams[ATTITUDE], log.streams[GROUND_VELOCITY]
    header = "%time,field.header.seq,field.header.stamp,field.header.frame_id,"
    for axis, column in (("roll", 0), ("pitch", 1)):
        rows = [[measured + swing, measured] for measured, swing in
                zip(np.degrees(attitude.values[:, column]), swing_of(attitude.times_s, 3.0),
                    strict=True)]
        write_alfa_topic(folder, f"nav_info-{axis}", header + "field.commanded,field.measured",
                         log.start_stamp_s + attitude.times_s, rows)
    commanded = velocity.values + swing_of(velocity.times_s, 0.5)[:, None]
    write_alfa_topic(folder, "nav_info-velocity",
                     header + "field.coordinate_frame,field.des_x,field.des_y,field.des_z,"
                     "field.meas_x,field.meas_y,field.meas_z",
                     log.start_stamp_s + velocity.times_s,
                     [[1, *c, *m] for c, m in zip(commanded, velocity.values, strict=True)])


def swing_of(times_s: np.ndarray, amplitude: float) -> np.ndarray:
    """A slow swing of the amplitude at the times [s]: a setpoint's lead on its aircraft."""
    return amplitude * np.sin(times_s / 2.0)


def write_alfa_topic(folder: Path, topic: str, header: str, stamps_s: np.ndarray,
                     rows: list) -> None:
    """FOLDER-mavros-TOPIC.csv as ALFA exports it: header, then per row its log time and
    header stamp (both stamps_s, in ns), sequence number, frame NED and the row's fields."""
    stamps_ns = np.round(stamps_s * 1e9).astype(np.int64)
    with (folder / f"{folder.name}-mavros-{topic}.csv").open("w") as file:
        file.write(header + "\n")
        file.writelines(f"{stamp},{k},{stamp},NED," + ",".join(repr(float(v)) for v in row)
                        + "\n" for k, (stamp, row) in enumerate(zip(stamps_ns, rows,
                                                                     strict=True)))


@pytest.fixture
def aileron_fault_ulog(aileron_fault_logs) -> Path:
    return aileron_fault_logs["ulg"][0]


def replay_argv(log: Path, airframe: Path | None, *extra: str) -> list[str]:
    """log_replay_node's command line (airframe None: the default, none)."""
    airframe_args = [] if airframe is None else ["-p", f"airframe:={airframe}"]
    return ros2_run_argv("uav_fault_estimator", "log_replay_node", ros_args=[
        "-p", f"log:={log}", *airframe_args, *extra])


@pytest.mark.slow
@pytest.mark.timeout(60)
@pytest.mark.parametrize("suffix", ["ulg"])
def test_detector_node_on_a_replayed_log_gives_the_offline_alarms(
        suffix, aileron_fault_logs, graph, start_process):
    log, start_s = aileron_fault_logs[suffix]
    # this test takes state too, so that the replay waits for it as for detector_node: its
    # air_data reader is then matched before the first message
    topics = graph.subscribe({"/faults/alarm": FaultAlarm, "/air_data": AirData,
                              "/state": AircraftState}, STREAM_QOS)
    alarms, air_data = topics["/faults/alarm"], topics["/air_data"]
    health = graph.subscribe({"/diagnostics": DiagnosticArray}, DIAGNOSTICS_QOS)["/diagnostics"]
    calibration = str(surface_calibration_path())  # these logs carry no setpoints
    start_process(ros2_run_argv("uav_fault_estimator", "detector_node", ros_args=[
        "-p", "wait_for_subscribers:=1", "-p", f"calibration_file:={calibration}"]),
        "detector_node")  # inputs once this test listens
    replay = start_process(replay_argv(log, FIXTURE_AIRFRAME,
                                       "-p", "real_time_factor:=0",
                                       "-p", "wait_for_subscribers:=2"), "log_replay_node")
    assert replay.wait(timeout_s=40) == 0, replay.output()

    inputs = detector_samples(read_log(log), load_airframe(FIXTURE_AIRFRAME), 0.2)
    offline = run_detector(read_calibration(calibration), inputs.flight, 0.01)
    graph.spin(20.0, until=lambda: len(alarms) >= len(offline)
               and len(air_data) >= inputs.times_s.size)
    assert_alarms_are_the_cores(alarms, offline)
    # air_data: the log's airspeed on every grid point, the vanes' angles missing
    received = np.array([air_data_array(m) for m in air_data])
    np.testing.assert_allclose(received[:, 0], inputs.airspeed_mps, rtol=1e-12,
                               equal_nan=True)
    assert np.isnan(received[:, 1:]).all()
    # the resampling's warnings, each said once (the 2.9 Hz outputs are slower than the grid)
    output = replay.output()
    assert output.count("stream outputs is slower than the detector's grid") == 1, output
    combined = [m for m in alarms if m.combined_alarm]
    print(f"{log.name}: {inputs.times_s.size} grid samples replayed, {len(alarms)} alarm messages "
          f"(offline {len(offline)}); GLRT alarms {np.sum([m.alarm for m in alarms], axis=0)}, "
          f"parameter alarms {sum(m.parameter_alarm for m in alarms)}, combined "
          f"{len(combined)}, the first at "
          f"{stamp_seconds(combined[0].header.stamp) if combined else float('nan'):.1f} s "
          f"(fault at {FAULT_START_S - start_s:g} s of log time)")
    assert combined and stamp_seconds(combined[0].header.stamp) >= FAULT_START_S - start_s
    # the replay's health stamped in the log's time, as its /clock
    replay_stamps = [stamp_seconds(array.header.stamp) for array in health
                     if any(status.name == "/log_replay_node" for status in array.status)]
    assert replay_stamps and all(0.0 <= t <= inputs.times_s[-1] + 1e-6 for t in replay_stamps)


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_the_tracking_generators_run_through_the_graph_on_the_logs_setpoints(
        aileron_fault_logs, graph, start_process, tmp_path):
    """An ALFA flight folder (the bag's topics, with nav_info setpoints): log_replay_node
    publishes the setpoints, detector_node with a calibration of the paper's generators and
    the ALFA benchmark's (made from the log's part before the fault) gives the core's numbers
    on every sample."""
    log, _ = aileron_fault_logs["alfa"]
    inputs = detector_samples(read_log(log), load_airframe(FIXTURE_AIRFRAME), 0.2)
    before_fault = inputs.times_s < inputs.times_s[0] + 35.0
    calibration = calibrate([DetectorFlight(*(np.asarray(column)[before_fault]
                                             for column in inputs.flight))],
                            0.2, 0.995, 25, 10.0, generators=TRACKING_SET)
    calibration_file = tmp_path / "calibration.yaml"
    calibration_file.write_text(yaml.safe_dump(calibration_to_dict(calibration),
                                               sort_keys=False))
    topics = graph.subscribe({"/faults/alarm": FaultAlarm, "/autopilot_setpoints":
                              AutopilotSetpoints, "/state": AircraftState}, STREAM_QOS)
    alarms, setpoints = topics["/faults/alarm"], topics["/autopilot_setpoints"]
    start_process(ros2_run_argv("uav_fault_estimator", "detector_node", ros_args=[
        "-p", f"calibration_file:={calibration_file}",
        "-p", "wait_for_subscribers:=1"]), "detector_node")  # inputs once this test listens
    replay = start_process(replay_argv(log, FIXTURE_AIRFRAME, "-p", "real_time_factor:=0",
                                       "-p", "wait_for_subscribers:=2"), "log_replay_node")
    assert replay.wait(timeout_s=40) == 0, replay.output()

    offline = run_detector(calibration, inputs.flight, 0.01)
    graph.spin(20.0, until=lambda: len(alarms) >= len(offline)
               and len(setpoints) >= inputs.times_s.size)
    np.testing.assert_allclose(np.array([setpoints_array(m) for m in setpoints]),
                               inputs.setpoints, rtol=1e-12, equal_nan=True)
    assert np.isfinite(inputs.setpoints[:, :2]).any(axis=1).sum() > 0.9 * inputs.times_s.size
    assert {tuple(m.channel_names) for m in alarms} == {TRACKING_SET}
    assert_alarms_are_the_cores(alarms, offline)


@pytest.mark.slow
@pytest.mark.timeout(60)
@pytest.mark.parametrize("case", ["missing_log", "no_airframe_for_outputs", "bad_airframe"])
def test_a_bad_log_or_airframe_is_one_line_and_status_2(case, aileron_fault_ulog, tmp_path):
    bad_airframe = tmp_path / "airframe.yaml"
    bad_airframe.write_text("name: x\noutput_unit: pwm_us\n")  # no surfaces
    log, airframe, expected = {
        "missing_log": (tmp_path / "none.ulg", FIXTURE_AIRFRAME, "no such file or folder"),
        "no_airframe_for_outputs": (aileron_fault_ulog, None, "need an airframe file"),
        "bad_airframe": (aileron_fault_ulog, bad_airframe, str(bad_airframe)),
    }[case]
    result = subprocess.run(replay_argv(log, airframe), capture_output=True, text=True,
                            timeout=50)
    assert result.returncode == 2, result
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("log_replay_node: "), result.stderr
    assert expected in lines[0], lines[0]
