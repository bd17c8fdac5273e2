"""A live view of ROS topics in Foxglove: a Foxglove WebSocket server (foxglove-sdk) with one
channel per topic, fed serialized (CDR) messages as they arrive, nothing decoded on the way.

Each channel carries its type's full ros2msg definition (the main type, then each nested
type after a line of 80 '=' and `MSG: pkg/Name`, as MCAP's ros2msg profile has it), made by
the project's rosbags type store, so Foxglove decodes the project's own messages too.

With a ParameterStore the server has the parameters capability: Foxglove reads and sets the
graph's parameters by the names foxglove_bridge gives them, the node's fully qualified name,
'.', the parameter (`/sim_node.real_time_factor`). The protocol has no authentication: who
reaches the port is served, so setting is a policy (PARAMETER_SET_POLICIES,
parameter_set_allowed), by default allowed on a loopback address only; a refused set is
answered with the values unchanged and an error status. With sim_time it has the time capability:
the view broadcasts its clock (broadcast_time), which Foxglove's timeline follows.

The server (foxglove-sdk 0.30) speaks the subprotocol `foxglove.sdk.v1` alone: a client
offering only `foxglove.websocket.v1` is refused with HTTP 400, and the SDK has no setting
for it.
"""

from __future__ import annotations

import threading
from typing import Any, Protocol

import foxglove
from foxglove.websocket import (
    Capability,
    ChannelView,
    Client,
    Parameter,
    ServerListener,
    StatusLevel,
    WebSocketServer,
)
from rosbags.typesys.store import Typestore
from uav_common.loopback import is_loopback

ROS2MSG, CDR = "ros2msg", "cdr"  # schema and message encodings of a ROS 2 channel
SUBPROTOCOL = "foxglove.sdk.v1"  # the one subprotocol foxglove-sdk 0.30's server accepts
# Who may set parameters: clients of a server on a loopback address only, every client, or
# none (read only).
PARAMETER_SET_POLICIES = ("loopback_only", "always", "never")
SET_REFUSED = "setting parameters is off on this server (foxglove_node's allow_parameter_set)"


def parameter_set_allowed(host: str, policy: str) -> bool:
    """Whether clients of a server listening on host may set parameters under policy
    (PARAMETER_SET_POLICIES); ValueError for another policy."""
    if policy not in PARAMETER_SET_POLICIES:
        raise ValueError(f"allow_parameter_set {policy!r}: one of "
                         f"{', '.join(PARAMETER_SET_POLICIES)}")
    return policy == "always" or (policy == "loopback_only" and is_loopback(host))


def ros2msg_schema(typestore: Typestore, message_type: str) -> str:
    """The ros2msg definition of message_type ("pkg/msg/Name") with its dependencies;
    ValueError for a type the type store does not know."""
    if message_type not in typestore.fielddefs:
        raise ValueError(f"no definition of {message_type}")
    text, _md5 = typestore.generate_msgdef(message_type, ros_version=2)
    return text


def parameter_name(node_name: str, parameter: str) -> str:
    """Foxglove's name of a node's parameter: `/ns/node` and `a.b` give `/ns/node.a.b`."""
    return f"{node_name}.{parameter}"


def split_parameter_name(name: str) -> tuple[str, str]:
    """(node's fully qualified name, parameter) of a Foxglove parameter name; node names
    have no '.', so the first '.' after the last '/' ends it. ValueError for a name that is
    not of that form."""
    slash = name.rfind("/")
    dot = name.find(".", slash + 1)
    if slash < 0 or dot < 0 or dot == slash + 1 or dot == len(name) - 1:
        raise ValueError(f"'{name}' is not /node.parameter")
    return name[:dot], name[dot + 1:]


class ParameterStore(Protocol):
    """The graph's parameters by Foxglove name (parameter_name), as plain values (bool, int,
    float, str, bytes, lists of them; None: not set). Called from the server's thread; each
    call returns within a bounded time of the store's."""

    def get(self, names: list[str]) -> dict[str, Any]:
        """The values of names (all parameters of every node for no name); a name without a
        value (no such node or parameter, a node that did not answer) is left out."""

    def set(self, values: dict[str, Any]) -> tuple[dict[str, Any], list[str]]:
        """Ask each owning node to take the values; the values the nodes then hold (refused
        ones unchanged) and one line per refusal, saying why."""


class SubscribedClients(ServerListener):
    """The Foxglove server's listener: which clients are subscribed to at least one channel
    (ServerListener's no-ops for the other events). The server calls it from its own
    thread."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._channels: dict[int, set[int]] = {}  # client id -> subscribed channel ids

    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        with self._lock:
            self._channels.setdefault(client.id, set()).add(channel.id)

    def on_unsubscribe(self, client: Client, channel: ChannelView) -> None:
        """Also called for each of its channels when a client disconnects."""
        with self._lock:
            channels = self._channels.get(client.id, set())
            channels.discard(channel.id)
            if not channels:
                self._channels.pop(client.id, None)

    def count(self) -> int:
        with self._lock:
            return len(self._channels)


def foxglove_parameters(values: dict[str, Any]) -> list[Parameter]:
    """Plain values by name as Foxglove parameters (their types follow from the values)."""
    return [Parameter(name, value=value) for name, value in sorted(values.items())]


class ViewListener(SubscribedClients):
    """SubscribedClients that also answers Foxglove's parameter requests from a store (none:
    no parameters); sets only when settable. A refused set goes to the clients as a status
    (a node's refusal a warning, the server's an error)."""

    def __init__(self, parameters: ParameterStore | None, settable: bool = True) -> None:
        super().__init__()
        self.parameters = parameters
        self.settable = settable
        self.server: WebSocketServer | None = None  # set once started: for statuses

    def on_get_parameters(self, client: Client, param_names: list[str],
                          request_id: str | None = None) -> list[Parameter]:
        """The values of param_names, all parameters for none."""
        if self.parameters is None:
            return []
        return foxglove_parameters(self.parameters.get(list(param_names)))

    def on_set_parameters(self, client: Client, parameters: list[Parameter],
                          request_id: str | None = None) -> list[Parameter]:
        """Each parameter set on its node; the values the nodes hold afterwards. Not
        settable: nothing set, the values as they are, and SET_REFUSED as an error."""
        if self.parameters is None:
            return []
        names = [parameter.name for parameter in parameters]
        if not self.settable:
            self._status(SET_REFUSED, StatusLevel.Error)
            return foxglove_parameters(self.parameters.get(names))
        values, refusals = self.parameters.set(
            {parameter.name: parameter.get_value() for parameter in parameters})
        for refusal in refusals:
            self._status(refusal, StatusLevel.Warning)
        return foxglove_parameters(values)

    def _status(self, message: str, level: StatusLevel) -> None:
        if self.server is not None:
            self.server.publish_status(message, level)


class LiveView:
    """A running Foxglove WebSocket server on host:port (port 0: one the system chooses);
    topics are added as they appear, messages logged raw. The server, its channels and its
    clients belong to this view alone (a foxglove Context of its own). parameters: the
    store Foxglove reads and sets parameters in (None: no parameters capability),
    parameter_set who may set them (PARAMETER_SET_POLICIES; settable tells the outcome);
    sim_time: advertise the time capability, the clients then following broadcast_time.

    RuntimeError (foxglove's, naming the cause) when the server cannot listen there;
    ValueError for an unknown policy."""

    def __init__(self, typestore: Typestore, host: str, port: int, name: str,
                 parameters: ParameterStore | None = None, sim_time: bool = False,
                 parameter_set: str = "loopback_only") -> None:
        self.typestore = typestore
        self.settable = parameter_set_allowed(host, parameter_set)
        self.context = foxglove.Context()
        self.clients = ViewListener(parameters, self.settable)
        capabilities = ([Capability.Parameters] if parameters is not None else []) + (
            [Capability.Time] if sim_time else [])
        self.server = foxglove.start_server(name=name, host=host, port=port,
                                            capabilities=capabilities, context=self.context,
                                            server_listener=self.clients)
        self.clients.server = self.server
        self.host = host
        self.port = self.server.port
        self.channels: dict[str, foxglove.Channel] = {}
        self.counts: dict[str, int] = {}  # messages logged per topic

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def add_topic(self, topic: str, message_type: str) -> None:
        """Advertise a topic of type message_type ("pkg/msg/Name") to the clients; ValueError
        for a type the type store does not know."""
        schema = foxglove.Schema(name=message_type, encoding=ROS2MSG,
                                 data=ros2msg_schema(self.typestore, message_type).encode())
        self.channels[topic] = foxglove.Channel(topic, message_encoding=CDR, schema=schema,
                                                context=self.context)
        self.counts[topic] = 0

    def log(self, topic: str, log_time_ns: int, data: bytes) -> None:
        """One serialized (CDR) message of an added topic, at log_time_ns [ns], to the
        clients subscribed to it."""
        self.channels[topic].log(data, log_time=log_time_ns)
        self.counts[topic] += 1

    def broadcast_time(self, time_ns: int) -> None:
        """The server's time [ns] to every client (with sim_time: Foxglove's current time)."""
        self.server.broadcast_time(time_ns)

    def publish_parameters(self, values: dict[str, Any]) -> None:
        """Changed parameter values by Foxglove name to the clients subscribed to them."""
        self.server.publish_parameter_values(foxglove_parameters(values))

    def close(self) -> None:
        """Stop the server (clients are disconnected) and close the channels. Safe to call
        twice."""
        self.server.stop()
        for channel in self.channels.values():
            channel.close()
        self.channels.clear()
