"""A flight log as its autopilot's messages (log_messages) and their player (log_streamer):
an ALFA-layout folder's rows become the messages MAVROS made them from, read back by
autopilot_messages to the same values; a ULog's topics become PX4's; boot times keep the
log's grid; the player paces and stays on loopback unless told."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from helpers import simulated_logs
from helpers.simulated_logs import ALFA
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from uav_fault_estimator.flight_logs.readers import read_log
from uav_fault_estimator.flight_logs.streams import ATTITUDE, BODY_RATES, OUTPUTS
from uav_mavlink.autopilot_messages import read_message
from uav_mavlink.log_messages import BOOT_AT_START_S, TimedMessage, log_messages
from uav_mavlink.log_streamer import main, on_loopback, play
from uav_mavlink.sample_assembly import ros_offset_ns
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import load_scenario

FLIGHT = "carbonZ_2018-01-01-00-00-00_no_failure"


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A 10 s simulated flight as a PX4 ULog and as an ALFA flight folder."""
    scenario = load_scenario(scenarios_dir() / "aileron_loss.yaml")
    scenario = type(scenario)(**{**scenario.__dict__, "duration_s": 10.0, "faults": ()})
    truth = simulated_logs.simulate_truth(scenario, 3)
    folder = tmp_path_factory.mktemp("logs")
    simulated_logs.write_ulog(folder / "flight.ulg", truth)
    simulated_logs.write_mavros_bag(folder / "flight.bag", truth, 3)
    simulated_logs.export_csv(folder / "flight.bag", folder / FLIGHT, ALFA)
    return {"ulog": folder / "flight.ulg", "alfa": folder / FLIGHT}


def parsed(timed: TimedMessage):
    """The message as the link carries it: packed and parsed."""
    sender, receiver = mavlink.MAVLink(None, 1, 1), mavlink.MAVLink(None)
    return receiver.decode(bytearray(timed.message.pack(sender)))


def by_type(messages: list[TimedMessage]) -> dict[str, list[TimedMessage]]:
    found: dict[str, list[TimedMessage]] = {}
    for timed in messages:
        found.setdefault(timed.message.get_type(), []).append(timed)
    return found


@pytest.mark.timeout(60)
def test_an_alfa_folder_becomes_arduplanes_messages_with_the_logs_values(logs):
    messages = log_messages(logs["alfa"])
    times = [timed.boot_time_s for timed in messages]
    assert times == sorted(times) and messages[0].message.get_type() == "HEARTBEAT"
    kinds = by_type(messages)
    assert {"ATTITUDE", "SERVO_OUTPUT_RAW", "VFR_HUD", "LOCAL_POSITION_NED"} <= set(kinds)
    log = read_log(logs["alfa"])  # as screen_logs.py reads it: FRD, NED, from its start
    rates = log.streams[BODY_RATES]  # imu/data's: this export has no imu/data_raw
    attitude = [read_message(parsed(timed)) for timed in kinds["ATTITUDE"]]
    np.testing.assert_allclose([[r.values[f"{axis}_rate"] for axis in ("roll", "pitch", "yaw")]
                                for r in attitude], rates.values, atol=1e-6)  # float32
    np.testing.assert_allclose([r.boot_time_s - BOOT_AT_START_S for r in attitude],
                               rates.times_s, atol=1e-3)  # whole ms
    outputs = log.streams[OUTPUTS]
    readings = [read_message(parsed(timed)) for timed in kinds["SERVO_OUTPUT_RAW"]]
    np.testing.assert_array_equal(
        [[r.values[f"output_{n}"] for n in range(1, outputs.values.shape[1] + 1)]
         for r in readings], outputs.values)
    roll = np.array([r.values["roll"] for r in attitude])
    assert np.all(np.abs(roll) < math.pi) and np.std(roll) > 0


@pytest.mark.timeout(60)
def test_a_ulog_becomes_px4s_messages_at_its_attitude_instants(logs):
    messages = log_messages(logs["ulog"])
    kinds = by_type(messages)
    log = read_log(logs["ulog"])
    attitude = log.streams[ATTITUDE]
    assert [t.boot_time_s - BOOT_AT_START_S for t in kinds["ATTITUDE"]] == pytest.approx(
        list(attitude.times_s), abs=1e-9)
    readings = [read_message(parsed(timed)) for timed in kinds["ATTITUDE"]]
    np.testing.assert_allclose([[r.values[name] for name in ("roll", "pitch")]
                                for r in readings], attitude.values[:, :2], atol=1e-6)
    assert all(t.message.autopilot == mavlink.MAV_AUTOPILOT_PX4 for t in kinds["HEARTBEAT"])


def test_boot_time_maps_to_ros_time_in_whole_seconds():
    offset = ros_offset_ns(1_700_000_000_400_000_000, 60_200_000_000)
    assert offset % 1_000_000_000 == 0
    assert (60_200_000_000 + offset) % 200_000_000 == 0  # still on the 0.2 s grid


def test_a_position_target_carries_the_commanded_velocity_unless_masked():
    velocity = mavlink.MAVLink_position_target_global_int_message(
        1500, 5, 1 | 2 | 4 | 64 | 128 | 256 | 1024 | 2048, 0, 0, 0.0, 1.0, 2.0, -0.5, 0, 0, 0,
        0, 0)
    reading = read_message(velocity)
    assert reading.boot_time_s == 1.5 and reading.values["velocity_down_mps"] == -0.5
    velocity.type_mask |= 8
    assert read_message(velocity) is None


@pytest.mark.parametrize(("connection", "local"), [
    ("udpout:127.0.0.1:14550", True), ("tcp:localhost:5760", True), ("udpout:[::1]:1", True),
    ("udpout:10.0.0.2:14550", False), ("udpbcast:127.255.255.255:14550", False),
    ("/dev/ttyACM0,921600", False), ("udpout:example.org:14550", False)])
def test_only_loopback_connections_are_taken_by_default(connection, local):
    assert on_loopback(connection) is local


def test_a_connection_beyond_loopback_is_refused_in_one_line(capsys, logs):
    assert main([str(logs["alfa"]), "--connection", "udpout:192.0.2.1:14550"]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_the_player_sends_each_message_when_its_time_comes_at_the_speed():
    now = [0.0]
    sent = []
    messages = [TimedMessage(t, name) for t, name in ((10.0, "a"), (10.5, "b"), (12.0, "c"))]
    play(messages, lambda m: sent.append((now[0], m)), 10.0, clock=lambda: now[0],
         sleep=lambda s: now.__setitem__(0, now[0] + s))
    assert sent == [(0.0, "a"), (pytest.approx(0.05), "b"), (pytest.approx(0.2), "c")]
