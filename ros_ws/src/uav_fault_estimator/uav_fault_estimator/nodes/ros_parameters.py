"""The graph's parameters through each node's standard parameter services (rcl_interfaces
ListParameters, GetParameters, SetParameters), by Foxglove name (`/sim_node.real_time_factor`):
the ParameterStore foxglove_node gives its LiveView.

The calls are made from the Foxglove server's thread on a hidden node of their own, spun
there by an executor of its own, so the node serving the topics is never touched from that
thread. A Foxglove request makes at most two rounds of calls (list then get, or set then
get), each to every node concerned at once and waiting at most timeout_s: a node that has
not answered by then is left out, said in the log; a node not in the graph is not waited
for.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import rclpy
from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters, ListParameters, SetParameters
from rclpy.client import Client
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter, parameter_value_to_python
from rclpy.task import Future

from uav_fault_estimator.viewing.live_view import parameter_name, split_parameter_name

SPIN_S = 0.01  # longest wait for one response before the deadline is looked at again [s]
SERVICES = {ListParameters: "list_parameters", GetParameters: "get_parameters",
            SetParameters: "set_parameters"}


def plain_value(value: ParameterValue) -> Any:
    """A ParameterValue as a plain value (a byte array as bytes; None: not set)."""
    plain = parameter_value_to_python(value)
    return b"".join(plain) if value.type == ParameterType.PARAMETER_BYTE_ARRAY else plain


def parameter_message(name: str, value: Any) -> Any:
    """rcl_interfaces/msg/Parameter of a plain value; its type follows from the value.
    TypeError for a value no parameter type holds (e.g. an empty or mixed list)."""
    return Parameter(name, value=value).to_parameter_msg()


def by_node(names: list[str]) -> tuple[dict[str, list[str]], list[str]]:
    """Foxglove names grouped by node ({node: [parameter, ...]}) and the names that are not
    /node.parameter."""
    grouped: dict[str, list[str]] = {}
    malformed = []
    for name in names:
        try:
            node_name, parameter = split_parameter_name(name)
        except ValueError:
            malformed.append(name)
            continue
        grouped.setdefault(node_name, []).append(parameter)
    return grouped, malformed


class RosParameters:
    """ParameterStore of the nodes in node's graph that serve parameters (hidden ones, ours
    among them, aside); requests are taken one at a time, each round of calls within
    timeout_s [s, wall time]."""

    def __init__(self, node: Node, timeout_s: float) -> None:
        self._node = node
        self._timeout_s = timeout_s
        self._caller = rclpy.create_node(f"_{node.get_name()}_parameters",
                                         namespace=node.get_namespace(),
                                         context=node.context,
                                         start_parameter_services=False)
        self._executor = SingleThreadedExecutor(context=node.context)
        self._executor.add_node(self._caller)
        self._clients: dict[tuple[str, type], Client] = {}
        self._lock = threading.Lock()  # one request at a time on the caller's executor

    def nodes(self) -> list[str]:
        """Fully qualified names of the graph's visible nodes that serve parameters."""
        services = {name for name, _types in self._node.get_service_names_and_types()}
        names = [f"{namespace.rstrip('/')}/{name}"
                 for name, namespace in self._node.get_node_names_and_namespaces()
                 if not name.startswith("_")]
        return sorted(name for name in names if f"{name}/list_parameters" in services)

    def get(self, names: list[str]) -> dict[str, Any]:
        with self._lock:
            if names:
                wanted, _malformed = by_node(names)
            else:
                listed = self._call_each(ListParameters, {
                    node_name: ListParameters.Request() for node_name in self.nodes()})
                wanted = {node_name: list(response.result.names)
                          for node_name, response in listed.items()}
            return self._values(wanted)

    def set(self, values: dict[str, Any]) -> tuple[dict[str, Any], list[str]]:
        with self._lock:
            grouped, malformed = by_node(list(values))
            refusals = [f"cannot set {name}: not /node.parameter" for name in malformed]
            present = self.nodes()
            refusals += [f"cannot set {parameter_name(node_name, parameter)}: no node "
                         f"{node_name} serves parameters" for node_name, parameters
                         in grouped.items() if node_name not in present
                         for parameter in parameters]
            grouped = {name: parameters for name, parameters in grouped.items()
                       if name in present}
            requests = {}
            for node_name, parameters in grouped.items():
                messages = []
                for parameter in parameters:
                    name = parameter_name(node_name, parameter)
                    try:
                        messages.append(parameter_message(parameter, values[name]))
                    except (TypeError, ValueError) as error:
                        refusals.append(f"cannot set {name}: {error}")
                if messages:
                    requests[node_name] = SetParameters.Request(parameters=messages)
            answered = self._call_each(SetParameters, requests)
            for node_name, request in requests.items():
                if node_name not in answered:
                    refusals.append(f"cannot set parameters of {node_name}: no answer")
                    continue
                for message, result in zip(request.parameters, answered[node_name].results,
                                           strict=True):
                    if not result.successful:
                        refusals.append(f"{parameter_name(node_name, message.name)} refused: "
                                        f"{result.reason}")
            for refusal in refusals:
                self._node.get_logger().warning(refusal)
            return self._values(grouped), refusals

    def _values(self, wanted: dict[str, list[str]]) -> dict[str, Any]:
        """The values of each node's wanted parameters by Foxglove name (unset ones, and
        those of nodes not in the graph, left out)."""
        present = self.nodes()
        answered = self._call_each(GetParameters, {
            node_name: GetParameters.Request(names=parameters)
            for node_name, parameters in wanted.items() if parameters and node_name in present})
        values = {}
        for node_name, response in answered.items():
            for parameter, value in zip(wanted[node_name], response.values, strict=True):
                if plain_value(value) is not None:
                    values[parameter_name(node_name, parameter)] = plain_value(value)
        return values

    def _call_each(self, service_type: type, requests: dict[str, Any]) -> dict[str, Any]:
        """Each node's service of service_type called with its request, all at once (each
        as soon as its service is ready); the responses by node of those that answered
        within timeout_s."""
        deadline = time.monotonic() + self._timeout_s
        waiting = dict(requests)  # not yet sent: the service not ready (discovery) so far
        futures: dict[str, Future] = {}
        while time.monotonic() < deadline:
            for node_name in [name for name in waiting
                              if self._client(name, service_type).service_is_ready()]:
                futures[node_name] = self._client(node_name, service_type).call_async(
                    waiting.pop(node_name))
            if not waiting and all(future.done() for future in futures.values()):
                break
            self._executor.spin_once(
                timeout_sec=max(0.0, min(SPIN_S, deadline - time.monotonic())))
        answered = {name: future.result() for name, future in futures.items()
                    if future.done() and future.result() is not None}
        late = sorted(set(requests) - set(answered))
        if late:
            self._node.get_logger().warning(
                f"no answer to {SERVICES[service_type]} within {self._timeout_s:g} s from "
                f"{', '.join(late)}")
        for node_name in set(late) & set(futures):
            self._client(node_name, service_type).remove_pending_request(futures[node_name])
        return answered

    def _client(self, node_name: str, service_type: type) -> Client:
        """The caller's client of a node's parameter service (made once, then kept)."""
        key = (node_name, service_type)
        if key not in self._clients:
            self._clients[key] = self._caller.create_client(
                service_type, f"{node_name}/{SERVICES[service_type]}")
        return self._clients[key]

    def close(self) -> None:
        """Stop the executor and the caller node (after the server has stopped)."""
        self._executor.shutdown(timeout_sec=0.0)
        self._caller.destroy_node()
