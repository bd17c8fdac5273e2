"""MAVProxy, the ground station on PyPI, as the router between an autopilot and
mavlink_node (docs/onboard.md, "A ground station between"): the autopilot's streams reach
the node through it and become the project's streams, and the node's estimates
(NAMED_VALUE_FLOAT) and alarm texts (STATUSTEXT) reach the ground station's side, shown on
its console with `watch` and written to its telemetry log, each text whole."""

from __future__ import annotations

import os
import shutil

import pytest
from helpers.scripted_autopilot import STEP_S, ScriptedArduPlane, run_steps, start_node
from uav_common.channels import DETECTION_THRESHOLD_PCT, PAPER_FAULT_NAMES
from uav_common.loopback import free_udp_port
from uav_common.ros.messages import header
from uav_common.ros.qos import STREAM_QOS
from uav_fault_msgs.msg import FaultAlarm, FaultEstimate

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

pytestmark = pytest.mark.integration


def mavproxy_argv(autopilot_port: int, node_port: int, state_dir) -> list[str]:
    """MAVProxy as docs/onboard.md starts it: the autopilot its master, the node an output,
    no interactive shell, the suite's messages watched on its console, no stream requests
    to the autopilot (the test's autopilot streams by itself)."""
    return [shutil.which("mavproxy.py"), f"--master=udpin:127.0.0.1:{autopilot_port}",
            f"--out=udpout:127.0.0.1:{node_port}", "--daemon", "--non-interactive",
            "--streamrate=-1", f"--state-basedir={state_dir}", "--logfile=flight.tlog",
            "--cmd=watch STATUSTEXT NAMED_VALUE_FLOAT"]


@pytest.mark.timeout(180)
def test_estimates_and_alarms_reach_mavproxy_between_autopilot_and_node(
        start_process, graph, tmp_path):
    autopilot_port, node_port = free_udp_port(), free_udp_port()
    mavproxy = start_process(mavproxy_argv(autopilot_port, node_port, tmp_path), "mavproxy")
    node, received = start_node(start_process, graph, node_port)
    autopilot = ScriptedArduPlane(autopilot_port, boot_s=10.0)
    estimates = graph.node.create_publisher(FaultEstimate, "/faults/estimate", STREAM_QOS)
    alarms = graph.node.create_publisher(FaultAlarm, "/faults/alarm", STREAM_QOS)
    try:
        run_steps(graph, autopilot, 20)  # MAVProxy hears the autopilot, then forwards
        assert graph.wait("the node's streams through MAVProxy",
                          lambda: len(received["/state"]) > 5, 30), (
            mavproxy.output() + node.output())
        assert graph.wait("the node subscribed", lambda: estimates.get_subscription_count()
                          and alarms.get_subscription_count(), 30), node.output()
        over = DETECTION_THRESHOLD_PCT + 10.0
        for step in range(80):  # 4 s: lift over the threshold from 1 s, an alarm from 2 s
            time_s = 10.0 + step * STEP_S
            estimates.publish(FaultEstimate(header=header(time_s),
                                            names=list(PAPER_FAULT_NAMES),
                                            values_pct=[over if step >= 20 else 0.5, 0.25,
                                                        -0.5, 1.0]))
            alarms.publish(FaultAlarm(
                header=header(time_s), channel_names=["roll_tracking"], alarm=[False],
                parameter_deviation=[0.0], parameter_threshold=2.0, fast_alarm=[step >= 40],
                template_kinds=["elevator"], template_alarm=[step >= 40],
                combined_alarm=step >= 40, cause="elevator" if step >= 40 else ""))
            run_steps(graph, autopilot, 1)
        expected = [f"UAV FDI: rw_lift {over:.2f}% over {DETECTION_THRESHOLD_PCT:g}%",
                    "UAV FDI alarm: elevator (fast,shape)"]
        assert graph.wait("MAVProxy shows both texts", lambda: all(
            text in mavproxy.output() for text in expected), 15), (
            mavproxy.output() + node.output())
        assert "NAMED_VALUE_FLOAT" in mavproxy.output() and "rw_lift" in mavproxy.output()
    finally:
        graph.node.destroy_publisher(estimates)
        graph.node.destroy_publisher(alarms)
    tlog = next(tmp_path.rglob("flight.tlog"))
    log = mavutil.mavlink_connection(str(tlog), dialect="ardupilotmega")
    logged = []
    while (message := log.recv_match(type=["STATUSTEXT", "NAMED_VALUE_FLOAT"])) is not None:
        logged.append(message)
    texts = [(m.get_srcComponent(), m.text) for m in logged if m.get_type() == "STATUSTEXT"]
    assert texts == [(mavutil.mavlink.MAV_COMP_ID_ONBOARD_COMPUTER, text) for text in expected]
    assert {m.name for m in logged if m.get_type() == "NAMED_VALUE_FLOAT"} == {
        "rw_lift", "rw_drag", "lw_lift", "lw_drag"}
