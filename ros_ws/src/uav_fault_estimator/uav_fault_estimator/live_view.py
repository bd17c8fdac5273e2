"""A live view of ROS topics in Foxglove: a Foxglove WebSocket server (foxglove-sdk) with one
channel per topic, fed serialized (CDR) messages as they arrive, nothing decoded on the way.

Each channel carries its type's full ros2msg definition (the main type, then each nested
type after a line of 80 '=' and `MSG: pkg/Name`, as MCAP's ros2msg profile has it), made by
the project's rosbags type store, so Foxglove decodes the project's own messages too.
"""

from __future__ import annotations

import threading

import foxglove
from foxglove.websocket import ChannelView, Client
from rosbags.typesys.store import Typestore

ROS2MSG, CDR = "ros2msg", "cdr"  # schema and message encodings of a ROS 2 channel


def ros2msg_schema(typestore: Typestore, message_type: str) -> str:
    """The ros2msg definition of message_type ("pkg/msg/Name") with its dependencies;
    ValueError for a type the type store does not know."""
    if message_type not in typestore.fielddefs:
        raise ValueError(f"no definition of {message_type}")
    text, _md5 = typestore.generate_msgdef(message_type, ros_version=2)
    return text


class SubscribedClients:
    """The Foxglove server's listener: which clients are subscribed to at least one channel.
    The server calls it from its own thread."""

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


class LiveView:
    """A running Foxglove WebSocket server on host:port (port 0: one the system chooses);
    topics are added as they appear, messages logged raw. The server, its channels and its
    clients belong to this view alone (a foxglove Context of its own).

    RuntimeError (foxglove's, naming the cause) when the server cannot listen there."""

    def __init__(self, typestore: Typestore, host: str, port: int, name: str) -> None:
        self.typestore = typestore
        self.context = foxglove.Context()
        self.clients = SubscribedClients()
        self.server = foxglove.start_server(name=name, host=host, port=port,
                                            context=self.context, server_listener=self.clients)
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

    def close(self) -> None:
        """Stop the server (clients are disconnected) and close the channels. Safe to call
        twice."""
        self.server.stop()
        for channel in self.channels.values():
            channel.close()
        self.channels.clear()
