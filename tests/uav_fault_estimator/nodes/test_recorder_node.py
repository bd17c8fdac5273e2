"""recorder_node beside sim_node: every message of every stream in a readable rosbag2
directory (MCAP), closed properly on SIGINT."""

from __future__ import annotations

import signal
import subprocess

import pytest
from rosbags.rosbag2 import Reader
from uav_common.package_data import default_parameters
from uav_common.ros.paced_publishing import ACK_EVERY_SAMPLES
from uav_common.ros_processes import (
    SIM_TIME_ROS_ARGS,
    fast_flight_ros_args,
    ros2_run_argv,
    wait_until,
)
from uav_fault_estimator.recording.project_bag import project_typestore

pytestmark = pytest.mark.integration

DURATION_S = 5.0
STREAMS = ("/state", "/controls", "/wind/filtered", "/faults/seeded", "/clock")


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_every_stream_message_is_recorded_and_readable(short_scenario, start_process,
                                                        tmp_path):
    bag = tmp_path / "flight"
    recorder = start_process(ros2_run_argv("uav_fault_estimator", "recorder_node", ros_args=[
        "-p", f"output_dir:={bag}", *SIM_TIME_ROS_ARGS]), "recorder_node")
    assert wait_until(lambda: bag.exists() or not recorder.running(), timeout_s=30)
    sim = start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=fast_flight_ros_args(
        short_scenario(DURATION_S), subscribers=1)), "sim_node")
    assert sim.wait(timeout_s=60) == 0, sim.output()
    assert recorder.stop(signal.SIGINT) == 0, recorder.output()

    typestore = project_typestore()
    counts: dict[str, int] = {}
    lags_s = []  # log time (the recorder's clock, on /clock) minus the header stamp
    with Reader(bag) as reader:
        for connection, log_ns, raw in reader.messages():
            message = typestore.deserialize_cdr(raw, connection.msgtype)  # every one decodes
            counts[connection.topic] = counts.get(connection.topic, 0) + 1
            if connection.topic == "/state":
                stamp = message.header.stamp
                lags_s.append((log_ns - stamp.sec * 10**9 - stamp.nanosec) * 1e-9)
        qos = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
    print(f"recorded: {counts}; /state logged {min(lags_s):.3f} to {max(lags_s):.3f} s "
          f"after its stamp; QoS of /state: {qos['/state']}")
    # sim time, never wall time (1.8e9 s): a sample is logged at the newest /clock the
    # recorder has taken, some samples either side of its stamp: the fast flight runs up to
    # ACK_EVERY_SAMPLES ahead between acknowledgements, and /clock (newest only) and the
    # queued streams' callbacks interleave (measured up to 0.1 s earlier in a CI run)
    ahead_s = ACK_EVERY_SAMPLES / default_parameters("uav_sim", "sim_node.yaml")["sensor_rate_hz"]
    assert min(lags_s) >= -0.5 and max(lags_s) <= ahead_s + 0.5
    for topic in STREAMS:  # each with its publisher's profile (DDS does not tell history)
        [profile] = qos[topic]
        assert (profile.reliability.name, profile.durability.name) == ("RELIABLE", "VOLATILE")
    expected = round(DURATION_S * 20) + 1
    for topic in STREAMS:
        assert counts.get(topic) == expected, topic
    assert "recording closed in" in recorder.output()


@pytest.mark.timeout(60)
def test_an_existing_output_dir_is_refused_with_one_message(tmp_path):
    result = subprocess.run(
        ros2_run_argv("uav_fault_estimator", "recorder_node",
                      ros_args=["-p", f"output_dir:={tmp_path}"]),
        capture_output=True, text=True, timeout=50,
    )
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert f"recorder_node: output_dir '{tmp_path}' must be given and must not exist" in (
        result.stderr)
