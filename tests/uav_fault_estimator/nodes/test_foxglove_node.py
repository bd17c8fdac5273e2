"""foxglove_node: a Foxglove WebSocket client on loopback sees the graph's topics advertised
with their ros2msg schemas and receives a published FaultEstimate unchanged (CDR); the
server listens on 127.0.0.1 alone and stops on SIGINT. Its core, LiveView, refuses a type it
cannot describe."""

from __future__ import annotations

import json
import re
import socket
import struct
import subprocess
import time

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from helpers.process_table import listening_tcp
from rclpy.serialization import deserialize_message
from uav_common.package_data import default_parameters
from uav_common.ros.node_tools import STREAM_QOS
from uav_common.ros_processes import ros2_run_argv
from uav_fault_estimator.live_view import LiveView
from uav_fault_estimator.recording.project_bag import project_typestore
from uav_fault_msgs.msg import FaultEstimate
from websockets.sync.client import ClientConnection, connect

TOPIC = "/faults/estimate"
SUBPROTOCOL = "foxglove.sdk.v1"  # the one foxglove-sdk 0.30's server accepts
MESSAGE_DATA = 0x01  # opcode of a binary server message carrying one message
MESSAGE_DATA_HEADER = struct.Struct("<BIQ")  # opcode, subscription id, log time [ns]
SUBSCRIPTION_ID = 7
SEPARATOR = "=" * 80  # between a ros2msg definition and each nested type's


def estimate() -> FaultEstimate:
    """A FaultEstimate with every field set."""
    message = FaultEstimate(
        names=["right_wing_lift_loss", "left_wing_drag_increase"], values_pct=[9.75, -0.5],
        solver_status=FaultEstimate.STATUS_MAX_ITERATIONS, updated=True, horizon=2,
        horizon_s=0.5, window_values_pct=[9.5, -0.25, 9.75, -0.5], iterations=31,
        solve_time_ms=0.625, update_cpu_time_ms=0.5)
    message.header.stamp.sec, message.header.stamp.nanosec = 123, 500_000_000
    message.header.frame_id = "base_link_frd"
    return message


def reported(diagnostics: list[DiagnosticArray]) -> dict[str, str]:
    """The values of foxglove_node's latest status on /diagnostics ({} before any)."""
    statuses = [status for array in diagnostics for status in array.status
                if status.name == "/foxglove_node"]
    return {value.key: value.value for value in statuses[-1].values} if statuses else {}


def channel_of(client: ClientConnection, topic: str, timeout_s: float) -> dict:
    """The channel the server advertises for topic (advertise ops, text frames)."""
    deadline = time.monotonic() + timeout_s
    while True:
        message = json.loads(client.recv(timeout=max(0.0, deadline - time.monotonic())))
        if message["op"] == "advertise":
            for channel in message["channels"]:
                if channel["topic"] == topic:
                    return channel


def message_data(client: ClientConnection, timeout_s: float) -> bytes | None:
    """The next MessageData frame within timeout_s (other frames skipped), or None."""
    deadline = time.monotonic() + timeout_s
    while (left_s := deadline - time.monotonic()) > 0:
        try:
            frame = client.recv(timeout=left_s)
        except TimeoutError:
            return None
        if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
            return frame
    return None


@pytest.mark.integration
@pytest.mark.timeout(60)
def test_a_client_receives_a_published_estimate_from_a_loopback_server(start_process, graph):
    node = start_process(ros2_run_argv("uav_fault_estimator", "foxglove_node", ros_args=[
        "-p", "port:=0", "-p", "discovery_period_s:=0.05"]), "foxglove_node")
    publisher = graph.node.create_publisher(FaultEstimate, TOPIC, STREAM_QOS)
    diagnostics = graph.subscribe({"/diagnostics": DiagnosticArray})["/diagnostics"]
    try:
        # the node subscribes once the topic has a publisher: this one
        assert graph.wait_for_subscribers(TOPIC, 1, timeout_s=30), node.output()
        # the default host: loopback alone (port 0: the one the system chose)
        [(address, port)] = listening_tcp(node.pid)
        assert address == "127.0.0.1"
        with connect(f"ws://127.0.0.1:{port}", subprotocols=[SUBPROTOCOL],
                     open_timeout=10) as client:
            server_info = json.loads(client.recv(timeout=10))
            channel = channel_of(client, TOPIC, timeout_s=10)
            assert server_info["op"] == "serverInfo"
            assert (channel["encoding"], channel["schemaName"], channel["schemaEncoding"]) == (
                "cdr", "uav_fault_msgs/msg/FaultEstimate", "ros2msg")
            # the definition, then each nested type's
            schema = channel["schema"]
            assert schema.startswith("uint8 STATUS_SOLVED=0\n")
            assert f"{SEPARATOR}\nMSG: std_msgs/Header\n" in schema
            assert f"{SEPARATOR}\nMSG: builtin_interfaces/Time\nint32 sec\n" in schema

            client.send(json.dumps({"op": "subscribe", "subscriptions": [
                {"id": SUBSCRIPTION_ID, "channelId": channel["id"]}]}))
            published = estimate()
            frame = None  # published until the subscription has reached the server
            while frame is None:
                publisher.publish(published)
                frame = message_data(client, timeout_s=0.2)
            # its health, with this client subscribed and the estimate forwarded
            graph.spin(5.0, until=lambda: reported(diagnostics).get("subscribed_clients") == "1")
            status = reported(diagnostics)
            assert status["subscribed_clients"] == "1", status
            assert int(status["messages_forwarded"]) >= 1 and int(status["topics"]) >= 1
        _, subscription_id, log_time_ns = MESSAGE_DATA_HEADER.unpack_from(frame)
        received = deserialize_message(frame[MESSAGE_DATA_HEADER.size:], FaultEstimate)
        assert received == published
        assert subscription_id == SUBSCRIPTION_ID
        assert abs(log_time_ns - time.time_ns()) < 10e9  # the node's clock: wall time here
    finally:
        graph.node.destroy_publisher(publisher)

    assert node.stop() == 0, node.output()
    assert re.search(rf"live view on ws://127.0.0.1:{port} stopped: .*{TOPIC} [1-9]",
                     node.output()), node.output()
    print(node.output())


@pytest.mark.integration
@pytest.mark.timeout(60)
def test_a_port_in_use_is_refused_with_one_message():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = subprocess.run(
            ros2_run_argv("uav_fault_estimator", "foxglove_node", ros_args=[
                "-p", f"port:={port}"]), capture_output=True, text=True, timeout=50)
    assert result.returncode == 2 and "Traceback" not in result.stderr, result.stderr
    assert f"foxglove_node: cannot serve on 127.0.0.1:{port}: " in result.stderr
    assert "Address already in use" in result.stderr


@pytest.mark.timeout(30)
def test_loopback_by_default_and_an_unknown_type_is_refused():
    assert default_parameters("uav_fault_estimator", "foxglove_node.yaml")["host"] == (
        "127.0.0.1")
    view = LiveView(project_typestore(), "127.0.0.1", 0, name="test")
    try:
        with pytest.raises(ValueError, match=r"^no definition of other_msgs/msg/Unknown$"):
            view.add_topic("/unknown", "other_msgs/msg/Unknown")
        assert view.channels == {} and view.counts == {}
    finally:
        view.close()
    view.close()  # twice is harmless
