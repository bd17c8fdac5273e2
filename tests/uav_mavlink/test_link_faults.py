"""mavlink_node on a link that fails as real ones do, against a scripted ArduPlane on UDP
loopback: packets failing their checksum and cut short, a ground station and a second
autopilot on the link, a reading out of order, a stream that stops and returns, the whole
link silent past the heartbeat timeout and back, and the autopilot rebooting. Each is said
once in the log and counted on /diagnostics, nothing crashes, the streams resume; the node
sends nothing but its heartbeat. Then the ground reports: estimates as NAMED_VALUE_FLOAT and
an alarm as STATUSTEXT, and still nothing that commands the aircraft."""

from __future__ import annotations

import os
import socket

import pytest
from helpers.diagnostics import latest_values
from helpers.scripted_autopilot import STEP_S, ScriptedArduPlane, run_steps, start_node
from uav_common.channels import DETECTION_THRESHOLD_PCT, PAPER_FAULT_NAMES
from uav_common.loopback import free_udp_port
from uav_common.ros.messages import header
from uav_common.ros.qos import STREAM_QOS
from uav_fault_msgs.msg import FaultAlarm, FaultEstimate

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil
from uav_mavlink.link import SENT_TYPES

pytestmark = pytest.mark.integration


def lines_with(output: str, text: str) -> list[str]:
    return [line for line in output.splitlines() if text in line]


@pytest.mark.timeout(120)
def test_each_fault_of_the_link_is_said_once_and_the_streams_resume(start_process, graph):
    port = free_udp_port()
    node, received = start_node(start_process, graph, port)
    autopilot = ScriptedArduPlane(port, boot_s=50.0)
    raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    ground_station = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}",
                                                source_system=255, source_component=190)
    second = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=2,
                                        source_component=1)
    run_steps(graph, autopilot, 20)
    assert graph.wait("streams", lambda: len(received["/state"]) > 5, 10), node.output()

    packet = autopilot.packed_attitude(autopilot.boot_s)
    for bad in (packet[:-1] + bytes([packet[-1] ^ 0xFF]), packet[:9]):  # checksum, cut short
        raw.sendto(bad, ("127.0.0.1", port))
        run_steps(graph, autopilot, 2)
    for _ in range(2):  # a ground station and a second autopilot, each twice
        ground_station.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS,
                                          mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 4)
        second.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_FIXED_WING,
                                  mavutil.mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 10, 4)
        second.mav.attitude_send(round(autopilot.boot_s * 1000), 1.0, 1.0, 1.0, 1.0, 1.0, 1.0)
        run_steps(graph, autopilot, 2)
    raw.sendto(autopilot.packed_attitude(autopilot.boot_s - 0.5), ("127.0.0.1", port))
    run_steps(graph, autopilot, 2)
    run_steps(graph, autopilot, 10, attitude=False)  # ATTITUDE stops for 0.5 s
    run_steps(graph, autopilot, 10)
    # the whole link silent past the heartbeat timeout (3 s), then back
    assert graph.wait("the link said lost",
                      lambda: lines_with(node.output(), "link lost: nothing from system 1"),
                      10), (
        node.output())
    run_steps(graph, autopilot, 20)
    autopilot.boot_s = 2.0  # the autopilot rebooted
    before_reboot = len(received["/state"])
    run_steps(graph, autopilot, 30)
    assert graph.wait("samples after the reboot",
                      lambda: len(received["/state"]) > before_reboot + 20, 10), node.output()
    graph.spin(2.0)
    output = node.output()
    print(output)

    assert node.running
    for said in ("packets failing their checksum or cut short", "system 255 (component 190)",
                 "system 2 (component 1)", "ATTITUDE came out of order",
                 "streams missing: attitude", "streams back: attitude",
                 "link lost: nothing from system 1", "link back after",
                 "it rebooted"):
        assert len(lines_with(output, said)) == 1, (said, output)
    values = latest_values(received["/diagnostics"], "/mavlink_node")
    assert int(values["bad_packets"]) == 2, values
    assert int(values["out_of_order"]) == 1 and int(values["reboots"]) == 1, values
    assert int(values["other_systems_messages"]) >= 4, values
    # silent for the last 2 s: each stream it sent is older than its maximum age
    assert (values["autopilot"], values["system"], values["stale"]) == (
        "ArduPilot", "1", "airspeed, attitude, outputs, position"), values
    assert received["/state"][-1].roll_rad == pytest.approx(0.1)
    assert {message.get_type() for message in autopilot.received} == {"HEARTBEAT"}


@pytest.mark.timeout(120)
def test_estimates_and_alarms_reach_the_ground_station_and_nothing_else_is_sent(
        start_process, graph):
    port = free_udp_port()
    node, _ = start_node(start_process, graph, port, "ground_estimates_hz:=2.0",
                         "ground_alarms:=true", "ground_text_interval_s:=1.0")
    estimates = graph.node.create_publisher(FaultEstimate, "/faults/estimate", STREAM_QOS)
    alarms = graph.node.create_publisher(FaultAlarm, "/faults/alarm", STREAM_QOS)
    try:
        assert graph.wait("the node subscribed", lambda: estimates.get_subscription_count()
                          and alarms.get_subscription_count(), 30), node.output()
        autopilot = ScriptedArduPlane(port, boot_s=10.0)
        over = DETECTION_THRESHOLD_PCT + 10.0
        for step in range(60):  # 3 s: the right wing's lift over the threshold from 1 s
            values = [over if step >= 20 else 0.5, 0.25, -0.5, 1.0]
            estimates.publish(FaultEstimate(names=list(PAPER_FAULT_NAMES), values_pct=values))
            alarms.publish(FaultAlarm(
                header=header(10.0 + step * STEP_S), channel_names=["roll", "pitch", "yaw"],
                alarm=[step >= 40, False, step >= 40], parameter_deviation=[3.0, 0.0, 3.0],
                parameter_threshold=2.0, fast_alarm=[False] * 3, combined_alarm=step >= 40,
                cause="aileron" if step >= 40 else ""))
            run_steps(graph, autopilot, 1)
        graph.spin(1.5)
        autopilot.collect()
    finally:
        graph.node.destroy_publisher(estimates)
        graph.node.destroy_publisher(alarms)
    print(node.output())

    kinds = {message.get_type() for message in autopilot.received}
    assert kinds == {"HEARTBEAT", "NAMED_VALUE_FLOAT", "STATUSTEXT"} and kinds <= SENT_TYPES
    named = [(m.name, m.value) for m in autopilot.received if m.get_type() == "NAMED_VALUE_FLOAT"]
    assert {name for name, _ in named} == {"rw_lift", "rw_drag", "lw_lift", "lw_drag"}
    assert 4 * 4 <= len(named) <= 4 * 8  # at most 2 Hz over 3 s (the first from the start)
    assert ("rw_lift", pytest.approx(over)) in named
    texts = [m.text for m in autopilot.received if m.get_type() == "STATUSTEXT"]
    assert texts == [f"UAV FDI: rw_lift {over:.2f}% over {DETECTION_THRESHOLD_PCT:g}%",
                     "UAV FDI alarm: aileron (glrt)"], texts
    assert all(m.severity == mavutil.mavlink.MAV_SEVERITY_WARNING
               for m in autopilot.received if m.get_type() == "STATUSTEXT")
