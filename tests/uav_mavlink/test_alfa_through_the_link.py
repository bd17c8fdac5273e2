"""Two of ALFA's development flights played live by log_streamer (10x) into mavlink_node
(carbon_z, ALFA's airframe file), with residual_node and detector_node on its streams: the
detector's alarms are, sample for sample, those of the same detector core run offline on
the same messages (studies/alfa_through_the_link.py's link path), and are set beside
screen_logs.py's of the same folder. Skipped where the flights are not on this machine."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from helpers.repo import REPO_ROOT
from uav_common.loopback import free_udp_port
from uav_common.message_fields import stamp_seconds
from uav_common.ros.qos import STREAM_QOS
from uav_common.ros_processes import ros2_run_argv
from uav_fault_estimator.detection.calibration_file import read_calibration
from uav_fault_estimator.flight_logs.screening_run import CalibrationRequest, calibrate_from_logs
from uav_fault_msgs.msg import FaultAlarm, Residuals
from uav_mavlink.autopilot_messages import ATTITUDE, OUTPUTS, POSITION

from studies.alfa_through_the_link import AIRFRAME, MAX_AGE_S, link_alarms, link_flight

pytestmark = pytest.mark.integration

ALFA_FLIGHTS = Path(os.environ.get("ALFA_FLIGHTS", "/work/shared/alfa/flights"))
FLIGHTS = ("carbonZ_2018-07-18-16-37-39_1_no_failure",  # 30 s
           "carbonZ_2018-09-11-15-05-11_1_elevator_failure")  # 76 s, alarms after the onset
SPEED = 10.0


@pytest.fixture(scope="module")
def calibration_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A calibration for ALFA's airframe from the two flights' fault-free parts, with the
    settings docs/flight_logs.md gives for ALFA."""
    if not all((ALFA_FLIGHTS / flight).is_dir() for flight in FLIGHTS):
        pytest.skip(f"ALFA's flights are not in {ALFA_FLIGHTS} (set ALFA_FLIGHTS)")
    path = tmp_path_factory.mktemp("alfa") / "alfa_cal.yaml"
    calibrate_from_logs(CalibrationRequest(
        tuple(ALFA_FLIGHTS / flight for flight in FLIGHTS), REPO_ROOT / AIRFRAME, path, "none",
        ("roll_tracking", "pitch_tracking", "climb_tracking", "lateral_force"), None, 0.95, 25,
        15.0))
    return path


@pytest.mark.timeout(90)
@pytest.mark.parametrize("flight", FLIGHTS)
def test_a_flight_streamed_live_gives_the_offline_link_alarms(
        flight, calibration_file, graph, start_process):
    folder = ALFA_FLIGHTS / flight
    port = free_udp_port()
    calibration = read_calibration(str(calibration_file), "carbon_z_alfa")
    offline = link_alarms(calibration, link_flight(folder, REPO_ROOT / AIRFRAME), 0.01)
    topics = graph.subscribe({"/faults/alarm": FaultAlarm, "/residuals": Residuals},
                             STREAM_QOS)
    ages = {ATTITUDE: "attitude_max_age_s", POSITION: "position_max_age_s",
            OUTPUTS: "outputs_max_age_s"}
    start_process(ros2_run_argv("uav_mavlink", "mavlink_node", ros_args=[
        "-p", f"connection:=udpin:127.0.0.1:{port}", "-p", "vehicle:=carbon_z",
        "-p", f"airframe:={REPO_ROOT / AIRFRAME}",
        *(arg for stream, name in ages.items() for arg in ("-p", f"{name}:={MAX_AGE_S[stream]}"))
    ]), "mavlink_node")
    start_process(ros2_run_argv("uav_fault_estimator", "detector_node", ros_args=[
        "-p", "vehicle:=carbon_z", "-p", "airframe:=carbon_z_alfa",
        "-p", f"calibration_file:={calibration_file}"]), "detector_node")
    residual = start_process(ros2_run_argv("uav_fault_estimator", "residual_node", ros_args=[
        "-p", "vehicle:=carbon_z"]), "residual_node")
    listeners = {"/state": 2, "/controls": 2, "/autopilot_setpoints": 1}  # the two nodes
    for topic, count in listeners.items():
        assert graph.wait(f"{topic} heard by {count}",
                          lambda topic=topic, count=count:
                          graph.node.count_subscribers(topic) >= count, 30)
    streamer = start_process(ros2_run_argv("uav_mavlink", "log_streamer", arguments=[
        str(folder), "--connection", f"udpout:127.0.0.1:{port}", "--speed", str(SPEED)]),
        "log_streamer")
    assert streamer.wait(timeout_s=30) == 0, streamer.output()
    alarms = topics["/faults/alarm"]
    graph.spin(20.0, until=lambda: len(alarms) >= len(offline))
    offline_samples = [offline[key] for key in sorted(offline)]
    assert len(alarms) == len(offline_samples)
    # ROS time is the boot time plus whole seconds (mavlink_node): the same grid
    offsets = {round(stamp_seconds(m.header.stamp) - s.time_s, 6)
               for m, s in zip(alarms, offline_samples, strict=True)}
    assert len(offsets) == 1 and float(offsets.pop()).is_integer()
    # lateral_force divides by the time between samples, which the float seconds of ROS
    # time (1.7e9 s) resolve to 0.24 us: its statistic differs by about 1e-5
    np.testing.assert_allclose([m.statistic for m in alarms],
                               [s.statistic for s in offline_samples], rtol=1e-4,
                               atol=1e-5, equal_nan=True)
    assert [m.combined_alarm for m in alarms] == [s.combined_alarm for s in offline_samples]
    print(f"{flight}: residual_node published {len(topics['/residuals'])} residuals")
    assert residual.running, residual.output()  # it takes the link's streams
