"""log_streamer's advice on a log's rates: the mavlink_node maximum ages they need (2.5 median
intervals, rounded up to 0.1 s; those above the node's defaults), said on its first line, and
with --write-params a parameter file the chain takes (the airframe, the detector's
calibration checked against it). An ALFA flight's, where ALFA's flights are on this machine."""

from __future__ import annotations

import math
import os
from pathlib import Path

import pytest
import yaml
from helpers.repo import REPO_ROOT
from uav_mavlink.autopilot_emulator import (
    attitude_message,
    heartbeat_message,
    local_position_ned_message,
    raw_imu_message,
    servo_output_raw_message,
    vfr_hud_message,
    wind_message,
)
from uav_mavlink.log_messages import TimedMessage
from uav_mavlink.log_streamer import (
    link_max_ages_s,
    listener_defaults_s,
    main,
    message_timings,
    raised_max_ages_s,
    rates_line,
)
from uav_mavlink.stream_rates import ARDUPILOT

ALFA_FLIGHTS = Path(os.environ.get("ALFA_FLIGHTS", "/work/shared/alfa/flights"))
ELEVATOR_FLIGHT = ALFA_FLIGHTS / "carbonZ_2018-09-11-15-05-11_1_elevator_failure"
CARBON_Z = REPO_ROOT / "ros_ws/src/uav_aircraft/aircraft/carbon_z"
ALFA_AIRFRAME = CARBON_Z / "airframes/carbon_z_alfa.yaml"
SHIPPED_CALIBRATION = CARBON_Z / "detector_calibration.yaml"


def streamed(rates_hz: dict[str, float], duration_s: float = 20.0) -> list[TimedMessage]:
    """Each message type at its rate [Hz] for duration_s, in time order, with a heartbeat
    each second (which the link does not sample)."""
    makers = {
        "ATTITUDE": lambda t: attitude_message(t, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
        "RAW_IMU": lambda t: raw_imu_message(t, (0.0, 0.0, 0.0), (0.0, 0.0, -9.8)),
        "SERVO_OUTPUT_RAW": lambda t: servo_output_raw_message(t, [1500.0] * 8),
        "LOCAL_POSITION_NED": lambda t: local_position_ned_message(
            t, (math.nan,) * 3, (15.0, 0.0, 0.0)),
        "VFR_HUD": lambda t: vfr_hud_message(15.0, 15.0, 0.0, 0.3, 100.0, 0.0),
        "WIND": lambda t: wind_message((1.0, 0.0, 0.0)),
        "HEARTBEAT": lambda t: heartbeat_message(ARDUPILOT),
    }
    messages = [TimedMessage(60.0 + k / hz, makers[kind](60.0 + k / hz))
                for kind, hz in {**rates_hz, "HEARTBEAT": 1.0}.items()
                for k in range(round(duration_s * hz))]
    return sorted(messages, key=lambda timed: timed.boot_time_s)


ALFA_LIKE_HZ = {"ATTITUDE": 2.5, "RAW_IMU": 10.0, "SERVO_OUTPUT_RAW": 3.0,
                "LOCAL_POSITION_NED": 4.0, "VFR_HUD": 2.5, "WIND": 1.0}
ADVISED_HZ = {"ATTITUDE": 25.0, "SERVO_OUTPUT_RAW": 10.0, "LOCAL_POSITION_NED": 10.0,
              "VFR_HUD": 10.0, "WIND": 2.0}  # docs/onboard.md's ArduPlane rates


@pytest.mark.timeout(30)
def test_each_max_age_is_two_and_a_half_of_its_slowest_messages_intervals():
    messages = streamed(ALFA_LIKE_HZ)
    assert set(message_timings(messages)) == set(ALFA_LIKE_HZ)  # the heartbeat: not read
    assert link_max_ages_s(message_timings(messages)) == {
        "attitude_max_age_s": (1.0, "ATTITUDE"),  # 2.5 x 0.4 s; RAW_IMU's 0.25 s is shorter
        "outputs_max_age_s": (0.9, "SERVO_OUTPUT_RAW"),  # 2.5 x 0.333 s = 0.83 s, rounded up
        "position_max_age_s": (0.7, "LOCAL_POSITION_NED"),  # 0.625 s
        "air_data_max_age_s": (1.0, "VFR_HUD"),
        "slow_max_age_s": (2.5, "WIND")}


@pytest.mark.timeout(30)
def test_only_the_ages_above_the_nodes_defaults_are_said_on_one_line():
    messages = streamed(ALFA_LIKE_HZ)
    defaults = listener_defaults_s()  # attitude 0.2, position and outputs 0.5, air data 1
    raised = raised_max_ages_s(link_max_ages_s(message_timings(messages)), defaults)
    assert list(raised) == ["attitude_max_age_s", "outputs_max_age_s", "position_max_age_s"]
    assert rates_line(raised, message_timings(messages)) == (
        "this log's rates (ATTITUDE 2.5 Hz, LOCAL_POSITION_NED 4.0 Hz, SERVO_OUTPUT_RAW 3.0 Hz) "
        "need mavlink_node --ros-args -p attitude_max_age_s:=1.0 -p outputs_max_age_s:=0.9 "
        "-p position_max_age_s:=0.7 (or in a parameter file: --write-params FILE)")
    advised = streamed(ADVISED_HZ)
    assert raised_max_ages_s(link_max_ages_s(message_timings(advised)), defaults) == {}
    assert rates_line({}, message_timings(advised)) == (
        "this log's rates: mavlink_node's default maximum ages hold")


@pytest.fixture()
def alfa_flight() -> Path:
    if not ELEVATOR_FLIGHT.is_dir():
        pytest.skip(f"ALFA's flights are not in {ALFA_FLIGHTS} (set ALFA_FLIGHTS)")
    return ELEVATOR_FLIGHT


@pytest.mark.timeout(60)
def test_an_alfa_flight_writes_the_parameters_the_chain_needs(alfa_flight, tmp_path, capsys):
    params = tmp_path / "alfa_link.yaml"
    assert main([str(alfa_flight), "--write-params", str(params),
                 "--airframe", str(ALFA_AIRFRAME)]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith("this log's rates (ATTITUDE 2.6 Hz, ") and (
        "-p attitude_max_age_s:=1.0 -p outputs_max_age_s:=0.9 -p position_max_age_s:=0.7"
        in first)
    assert yaml.safe_load(params.read_text()) == {
        "mavlink_node": {"ros__parameters": {
            "attitude_max_age_s": 1.0, "outputs_max_age_s": 0.9, "position_max_age_s": 0.7,
            "airframe": str(ALFA_AIRFRAME)}},
        # the vehicle's own calibration, of carbon_z_sim, is then refused, not run on the log
        "detector_node": {"ros__parameters": {"airframe": "carbon_z_alfa"}}}


@pytest.mark.timeout(60)
def test_a_calibration_of_another_airframe_is_refused_in_one_line(alfa_flight, tmp_path, capsys):
    params = tmp_path / "alfa_link.yaml"
    status = main([str(alfa_flight), "--write-params", str(params), "--airframe",
                   str(ALFA_AIRFRAME), "--detector-calibration", str(SHIPPED_CALIBRATION)])
    error = capsys.readouterr().err
    assert status == 2 and error.count("\n") == 1 and not params.exists()
    assert error.startswith(f"log_streamer: calibration file {SHIPPED_CALIBRATION} is for ")
    assert "'carbon_z_sim', not 'carbon_z_alfa'" in error
