"""foxglove_node: a Foxglove WebSocket client on loopback sees the graph's topics advertised
with their ros2msg schemas and receives a published FaultEstimate unchanged (CDR); the
server listens on 127.0.0.1 alone and stops on SIGINT. The client reads and sets the graph's
parameters (a live one taken by its node, a read-only one refused, unchanged, with the
node's reason as a status), hears of changes made with `ros2 param set`, and is sent the
simulation time; a node that does not answer costs a request no more than the timeout. The
clients offer both subprotocols, as Lichtblick from 1.22 does. Setting parameters follows
allow_parameter_set (off: refused with a status, nothing set). Its core, LiveView, refuses
a type it cannot describe and speaks foxglove.sdk.v1 alone."""

from __future__ import annotations

import json
import re
import socket
import struct
import subprocess
import threading
import time
from collections.abc import Callable

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from helpers.process_table import listening_port, listening_tcp
from helpers.ros2_cli import param_get, param_set
from rclpy.executors import SingleThreadedExecutor
from rclpy.serialization import deserialize_message
from uav_common.package_data import default_parameters
from uav_common.ros.qos import STREAM_QOS
from uav_common.ros_processes import ros2_run_argv
from uav_fault_estimator.recording.project_bag import project_typestore
from uav_fault_estimator.viewing.live_view import (
    SET_REFUSED,
    SUBPROTOCOL,
    LiveView,
    parameter_name,
    parameter_set_allowed,
    split_parameter_name,
)
from uav_fault_msgs.msg import FaultEstimate
from websockets.exceptions import InvalidStatus
from websockets.sync.client import ClientConnection, connect

TOPIC = "/faults/estimate"
MESSAGE_DATA = 0x01  # opcode of a binary server message carrying one message
MESSAGE_DATA_HEADER = struct.Struct("<BIQ")  # opcode, subscription id, log time [ns]
TIME = 0x02  # opcode of a binary server message carrying the server's time
TIME_MESSAGE = struct.Struct("<BQ")  # opcode, time [ns]
RATE = "/sim_node.real_time_factor"  # live
SENSOR_RATE = "/sim_node.sensor_rate_hz"  # read-only
SUBSCRIPTION_ID = 7
# What Lichtblick 1.22 offers: both names (older viewers offer the first alone: refused)
VIEWER_SUBPROTOCOLS = ["foxglove.websocket.v1", SUBPROTOCOL]
SEPARATOR = "=" * 80  # between a ros2msg definition and each nested type's
POLL_S = 0.05  # pause between two requests asked again until the graph has what they need [s]
REQUEST_TIMEOUT_S = 10.0  # longest wait for the answer to one Foxglove request [s]


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


def next_op(client: ClientConnection, ops: str, timeout_s: float) -> dict:
    """The next text message of one of ops ("a|b") within timeout_s (others, binary ones
    too, skipped); TimeoutError when none came."""
    deadline = time.monotonic() + timeout_s
    while True:
        frame = client.recv(timeout=max(0.0, deadline - time.monotonic()))
        if isinstance(frame, str) and (message := json.loads(frame))["op"] in ops.split("|"):
            return message


def next_time_ns(client: ClientConnection, timeout_s: float) -> int:
    """The time [ns] of the next Time message within timeout_s (other frames skipped)."""
    deadline = time.monotonic() + timeout_s
    while True:
        frame = client.recv(timeout=max(0.0, deadline - time.monotonic()))
        if isinstance(frame, bytes) and frame[0] == TIME:
            return TIME_MESSAGE.unpack_from(frame)[1]


def parameters(client: ClientConnection, op: dict,
               timeout_s: float) -> tuple[dict[str, object], list[str]]:
    """Send a getParameters or setParameters op (with an id); the values answered by name
    and the status messages that came before the answer (the server sends those first)."""
    client.send(json.dumps(op))
    deadline = time.monotonic() + timeout_s
    statuses = []
    while (answer := next_op(client, "parameterValues|status",
                             deadline - time.monotonic()))["op"] == "status":
        statuses.append(answer["message"])
    assert answer.get("id") == op["id"], answer
    return {parameter["name"]: parameter.get("value")
            for parameter in answer["parameters"]}, statuses


def handled(client: ClientConnection, timeout_s: float) -> None:
    """Return once the server has handled every op the client sent before this call.

    foxglove-sdk's server handles one client's ops in order, each to its end (a subscribe
    registered, a getParameters answered) before it reads the next one: so the answer to a
    getParameters sent now comes after the earlier ops took effect. The protocol has no
    acknowledgement of subscribe or subscribeParameterUpdates of its own. Asks for
    foxglove_node's own port (its own node: answered without a round trip to another
    process); fails on a status (an error about an earlier op) or no answer in timeout_s."""
    values, statuses = parameters(client, {"op": "getParameters", "id": "handled",
                                           "parameterNames": ["/foxglove_node.port"]},
                                  timeout_s)
    assert (values, statuses) == ({"/foxglove_node.port": 0}, []), (values, statuses)


def values_once_discovered(client: ClientConnection, op: dict,
                           done: Callable[[dict[str, object]], bool],
                           timeout_s: float) -> dict[str, object]:
    """The values answered to a getParameters op (parameters(), each answer within
    REQUEST_TIMEOUT_S), asked again every POLL_S until done(values) holds (foxglove_node
    answers for the nodes it has discovered so far) or timeout_s [s] passes; the last
    values either way, for the caller to assert on."""
    deadline = time.monotonic() + timeout_s
    values, _ = parameters(client, op, REQUEST_TIMEOUT_S)
    while not done(values) and time.monotonic() < deadline:
        time.sleep(POLL_S)  # between polls, not to busy-loop the server: done() decides
        values, _ = parameters(client, op, REQUEST_TIMEOUT_S)
    return values


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
        # the node subscribes once the topic has a publisher: this one. Waited for on the
        # publishing side (its own match count): from then on this publisher sends to the
        # node's subscription, which matched the publisher when created (the node saw the
        # publisher first), so nothing published later is lost on the way
        assert graph.wait(f"foxglove_node's subscription of {TOPIC} matched by this test's "
                          "publisher", lambda: publisher.get_subscription_count() >= 1,
                          timeout_s=30), node.output()
        # the default host: loopback alone (port 0: the one the system chose)
        [(address, port)] = listening_tcp(node.pid)
        assert address == "127.0.0.1"
        with connect(f"ws://127.0.0.1:{port}", subprotocols=VIEWER_SUBPROTOCOLS,
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
            handled(client, timeout_s=10)  # the server forwards the channel to this client
            published = estimate()
            publisher.publish(published)  # once: reliable, both ends matched, none lost
            frame = message_data(client, timeout_s=10)
            assert frame is not None, node.output()
            # its health, with this client subscribed and messages forwarded (a status every
            # second: waited for until one says so; messages_forwarded counts every topic's,
            # /rosout's and /diagnostics' too, so it is this estimate's only in the final log)
            assert graph.wait(
                "foxglove_node to report this client subscribed and messages forwarded",
                lambda: (reported(diagnostics).get("subscribed_clients") == "1"
                         and int(reported(diagnostics).get("messages_forwarded", 0)) >= 1),
                timeout_s=10), reported(diagnostics)
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
    assert re.search(rf"live view on ws://127.0.0.1:{port} stopped: .*{TOPIC} 1(,|$)",
                     node.output(), re.MULTILINE), node.output()
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


@pytest.mark.integration
@pytest.mark.timeout(120)
def test_a_client_reads_and_sets_parameters_and_follows_the_simulation_time(
        short_scenario, start_process):
    scenario = short_scenario(600.0)
    sim = start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=[
        "-p", f"scenario:={scenario}", "-p", "real_time_factor:=1.0",
        "-p", "wait_for_subscribers:=0"]), "sim_node")
    node = start_process(ros2_run_argv("uav_fault_estimator", "foxglove_node", ros_args=[
        "-p", "port:=0", "-p", "use_sim_time:=true"]), "foxglove_node")
    port = listening_port(node.pid, timeout_s=30)
    with connect(f"ws://127.0.0.1:{port}", subprotocols=VIEWER_SUBPROTOCOLS,
                 open_timeout=10) as client:
        server_info = next_op(client, "serverInfo", timeout_s=10)
        assert {"parameters", "parametersSubscribe", "time"} <= set(
            server_info["capabilities"]), server_info
        # simulation time, not wall time: the 600 s flight has just begun
        assert 0 < next_time_ns(client, timeout_s=30) < 600e9

        # foxglove_node leaves out the nodes it has not discovered: asked until it answers
        # for sim_node (both parameters are sim_node's: one answer has both or neither)
        ask = {"op": "getParameters", "parameterNames": [RATE, SENSOR_RATE], "id": "get"}
        values = values_once_discovered(client, ask, lambda values: values != {},
                                        timeout_s=30)
        assert values == {RATE: 1.0, SENSOR_RATE: 20.0}, sim.output()
        every, _ = parameters(client, {"op": "getParameters", "parameterNames": [],
                                       "id": "all"}, timeout_s=10)
        assert every[RATE] == 1.0 and every["/foxglove_node.port"] == 0
        assert every["/sim_node.scenario"] == str(scenario)

        values, statuses = parameters(client, {"op": "setParameters", "id": "set", "parameters": [
            {"name": RATE, "value": 4.0, "type": "float64"},
            {"name": SENSOR_RATE, "value": 10.0, "type": "float64"}]}, timeout_s=10)
        assert values == {RATE: 4.0, SENSOR_RATE: 20.0}
        assert statuses == [
            f"{SENSOR_RATE} refused: Trying to set a read-only parameter: sensor_rate_hz."]
        assert param_get("/sim_node", "real_time_factor") == "Double value is: 4.0"
        assert param_get("/sim_node", "sensor_rate_hz") == "Double value is: 20.0"
        # out of range: refused by the node, unchanged
        values, statuses = parameters(client, {"op": "setParameters", "id": "too fast",
                                               "parameters": [{"name": RATE, "value": 5000.0,
                                                               "type": "float64"}]}, timeout_s=10)
        assert values == {RATE: 4.0}
        assert statuses == [f"{RATE} refused: Parameter real_time_factor out of range Min: 0.0, "
                            "Max: 1000.0, value: 5000.0"]

        # a change made elsewhere reaches a client subscribed to the parameter. Before the
        # change: the server has taken the subscription (handled), and sim_node's
        # /parameter_events publisher has matched foxglove_node's subscription, which
        # foxglove_node made before its parameter clients: sim_node has answered those, so
        # it had discovered the subscription (Fast DDS announces a participant's endpoints
        # in order, on a reliable channel)
        client.send(json.dumps({"op": "subscribeParameterUpdates", "parameterNames": [RATE]}))
        handled(client, timeout_s=10)
        assert param_set("/sim_node", "real_time_factor", "2.0") == "Set parameter successful"
        update = next_op(client, "parameterValues", timeout_s=10)
        assert update["parameters"] == [{"name": RATE, "type": "float64", "value": 2.0}]
    assert node.stop() == 0, node.output()
    assert f"{SENSOR_RATE} refused: Trying to set a read-only parameter" in node.output()


@pytest.mark.integration
@pytest.mark.timeout(60)
def test_a_node_that_does_not_answer_costs_a_request_the_timeout_alone(start_process, graph):
    timeout_s = 0.5
    node = start_process(ros2_run_argv("uav_fault_estimator", "foxglove_node", ros_args=[
        "-p", "port:=0", "-p", f"parameter_timeout_s:={timeout_s}",
        "-p", "allow_parameter_set:=never"]), "foxglove_node")
    # A node of the test's, its parameter services served (by a thread of the test's) until
    # foxglove_node has discovered it, then by nobody: its requests wait for ever. Served
    # first because foxglove_node answers for the nodes it has discovered so far: a request
    # made before it knows of the node answers at once, and says nothing of a silent node.
    silent = rclpy.create_node("silent_node", context=graph.context)
    executor = SingleThreadedExecutor(context=graph.context)
    executor.add_node(silent)
    serving = threading.Event()
    serving.set()

    def serve() -> None:
        """Spin silent_node while serving is set (each spin_once at most 50 ms)."""
        while serving.is_set():
            executor.spin_once(timeout_sec=0.05)

    server = threading.Thread(target=serve, name="silent_node", daemon=True)
    server.start()
    try:
        port = listening_port(node.pid, timeout_s=30)
        with connect(f"ws://127.0.0.1:{port}", subprotocols=VIEWER_SUBPROTOCOLS,
                     open_timeout=10) as client:
            ask = {"op": "getParameters", "parameterNames": [], "id": "all"}
            values = values_once_discovered(
                client, ask, lambda values: "/silent_node.use_sim_time" in values,
                timeout_s=30)
            # foxglove_node has found silent_node and its list and get services
            assert values.get("/silent_node.use_sim_time") is False, values
            serving.clear()
            server.join()  # from here on silent_node answers nothing
            started = time.monotonic()
            values, _ = parameters(client, ask, timeout_s=10)
            took_s = time.monotonic() - started
            # allow_parameter_set never: a set is refused with a status, nothing set
            refused, statuses = parameters(client, {
                "op": "setParameters", "id": "set", "parameters": [
                    {"name": "/foxglove_node.discovery_period_s", "value": 1.0,
                     "type": "float64"}]}, timeout_s=10)
        assert values["/foxglove_node.port"] == 0
        assert not any(name.startswith("/silent_node.") for name in values)
        assert refused == {"/foxglove_node.discovery_period_s": 0.2}
        assert statuses == [SET_REFUSED]
        # listing waits timeout_s for the silent node; getting asks the others alone
        assert timeout_s <= took_s < 2 * timeout_s, took_s
        print(f"a request with a silent node took {took_s:.2f} s")
    finally:
        serving.clear()
        server.join()
        executor.shutdown()
        silent.destroy_node()
    assert node.stop() == 0, node.output()
    assert "no answer to list_parameters within 0.5 s from /silent_node" in node.output()


@pytest.mark.timeout(30)
def test_foxglove_parameter_names_are_the_node_then_the_parameter():
    assert parameter_name("/uav1/sim_node", "a.b") == "/uav1/sim_node.a.b"
    assert split_parameter_name("/uav1/sim_node.a.b") == ("/uav1/sim_node", "a.b")
    for bad in ("sim_node", "/sim_node", "/sim_node.", "/.x"):
        with pytest.raises(ValueError, match=r"is not /node\.parameter"):
            split_parameter_name(bad)


@pytest.mark.timeout(30)
def test_the_server_speaks_foxglove_sdk_v1_alone():
    view = LiveView(project_typestore(), "127.0.0.1", 0, name="test")
    try:
        # the subprotocol Foxglove's older clients and foxglove_bridge speak: refused
        with pytest.raises(InvalidStatus, match="HTTP 400"):
            connect(view.url, subprotocols=["foxglove.websocket.v1"], open_timeout=10)
        with connect(view.url, subprotocols=["foxglove.websocket.v1", SUBPROTOCOL],
                     open_timeout=10) as client:
            assert client.subprotocol == SUBPROTOCOL
            server_info = next_op(client, "serverInfo", timeout_s=10)
        # no store, no sim time: neither capability
        assert server_info["capabilities"] == []
    finally:
        view.close()


class FixedStore:
    """A ParameterStore of fixed values that records the sets asked of it."""

    def __init__(self, values: dict) -> None:
        self.values, self.sets = dict(values), []

    def get(self, names: list[str]) -> dict:
        return {name: value for name, value in self.values.items() if not names or name in names}

    def set(self, values: dict) -> tuple[dict, list[str]]:
        self.sets.append(values)
        self.values.update(values)
        return {name: self.values[name] for name in values}, []


@pytest.mark.timeout(30)
@pytest.mark.parametrize("policy", ["never", "always"])
def test_a_set_is_refused_with_a_status_when_off_and_taken_when_on(policy):
    store = FixedStore({RATE: 1.0})
    view = LiveView(project_typestore(), "127.0.0.1", 0, name="test", parameters=store,
                    parameter_set=policy)
    try:
        with connect(view.url, subprotocols=VIEWER_SUBPROTOCOLS, open_timeout=10) as client:
            values, statuses = parameters(client, {"op": "setParameters", "id": "set",
                                                   "parameters": [{"name": RATE, "value": 4.0,
                                                                   "type": "float64"}]},
                                          timeout_s=10)
    finally:
        view.close()
    if policy == "never":
        assert (values, statuses, store.sets) == ({RATE: 1.0}, [SET_REFUSED], [])
    else:
        assert (values, statuses, store.sets) == ({RATE: 4.0}, [], [{RATE: 4.0}])


@pytest.mark.timeout(30)
def test_sets_are_allowed_by_default_on_loopback_alone():
    assert default_parameters("uav_fault_estimator", "foxglove_node.yaml")[
        "allow_parameter_set"] == "loopback_only"
    for host, allowed in (("127.0.0.1", True), ("::1", True), ("localhost", True),
                          ("0.0.0.0", False), ("10.0.0.1", False), ("viewer.lan", False)):
        assert parameter_set_allowed(host, "loopback_only") == allowed, host
        assert parameter_set_allowed(host, "always") and not parameter_set_allowed(host,
                                                                                  "never")
    with pytest.raises(ValueError, match="one of loopback_only, always, never"):
        parameter_set_allowed("127.0.0.1", "sometimes")
