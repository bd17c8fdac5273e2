"""foxglove_node: serves every topic of the graph live on the Foxglove WebSocket protocol.

Topics are discovered while the node runs and subscribed raw, as recorder_node does
(RawTopics: once they have publishers, with the reliability those offer, keep-all); each
message goes unchanged (CDR) to its channel of a LiveView, stamped with the receive time on
the node's clock (simulation time when started with use_sim_time, as bringup.sh starts it).
The graph's parameters are read and set through the nodes' parameter services (RosParameters),
and changes any tool makes (/parameter_events) go to the clients subscribed to them; clients
set them only where allow_parameter_set says (by default on a loopback host alone). The
protocol has no authentication: off loopback, the node says so once (log and /diagnostics
WARN). Under
use_sim_time the server's time is the node's clock, broadcast every TIME_PERIOD_S.
Connect Foxglove to ws://HOST:PORT. Reports on /diagnostics; SIGINT stops the server.
"""

from __future__ import annotations

import sys

from rcl_interfaces.msg import ParameterEvent
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import qos_profile_parameter_events
from rclpy.topic_endpoint_info import TopicEndpointInfo
from uav_common.loopback import is_loopback
from uav_common.ros.diagnostics import OK, WARN, Diagnostics
from uav_common.ros.node_life import run_node
from uav_common.ros.parameters import ParameterSpec, declare_parameters

from uav_fault_estimator.nodes.raw_topics import RawTopics
from uav_fault_estimator.nodes.ros_parameters import RosParameters, plain_value
from uav_fault_estimator.recording.project_bag import project_typestore
from uav_fault_estimator.viewing.live_view import PARAMETER_SET_POLICIES, LiveView, parameter_name

PARAMETERS = {
    "host": ParameterSpec("address the WebSocket server listens on (127.0.0.1: this machine "
                          "only; 0.0.0.0 opens it to the network, unauthenticated: anyone "
                          "who reaches the port sees every topic; docs/security.md)",
                          "127.0.0.1"),
    "allow_parameter_set": ParameterSpec(
        "who may set the graph's parameters through the view: loopback_only (clients of a "
        "server on a loopback host), always (any client that reaches the port), never "
        "(read only)", "loopback_only", choices=PARAMETER_SET_POLICIES),
    "port": ParameterSpec("TCP port the WebSocket server listens on (0: one the system "
                          "chooses, logged)", 8765, 0, 65535),
    "discovery_period_s": ParameterSpec(
        "how often new topics are looked for [s, wall time]", 0.2, 0.01, 60.0),
    "parameter_timeout_s": ParameterSpec(
        "longest one round of calls of a Foxglove parameter request waits for the "
        "nodes' answers [s, wall time]", 2.0,
        0.1, 30.0),
}
REPORT_PERIOD_S = 1.0  # how often the diagnostics' counters are refreshed [s, wall time]
TIME_PERIOD_S = 0.05  # how often the server's time is broadcast [s, wall time]: 20 Hz


class FoxgloveNode(Node):
    """Thin adapter: the graph's topics (RawTopics) into one LiveView."""

    def __init__(self) -> None:
        super().__init__("foxglove_node")
        self.parameters = declare_parameters(self, PARAMETERS)
        host, port = self.parameters["host"], self.parameters["port"]
        self.ros_parameters = RosParameters(self, self.parameters["parameter_timeout_s"])
        sim_time = self.get_parameter("use_sim_time").value
        try:
            self.live_view = LiveView(project_typestore(), host, port,
                                      name=self.get_fully_qualified_name(),
                                      parameters=self.ros_parameters, sim_time=sim_time,
                                      parameter_set=self.parameters["allow_parameter_set"])
        except RuntimeError as error:  # foxglove's: the address is taken, unknown, ...
            self.ros_parameters.close()
            raise ValueError(f"cannot serve on {host}:{port}: {error}") from None
        self.get_logger().info(f"serving the graph's topics and parameters on "
                               f"{self.live_view.url}; clients "
                               f"{'may' if self.live_view.settable else 'may not'} set "
                               "parameters")
        self.exposure = "" if is_loopback(host) else (
            f"unauthenticated on {host}: anyone who reaches port {self.live_view.port} sees "
            f"every topic{' and sets parameters' if self.live_view.settable else ''} "
            "(docs/security.md: an SSH tunnel to 127.0.0.1 instead)")
        if self.exposure:
            self.get_logger().warning(self.exposure)
        self.create_subscription(ParameterEvent, "/parameter_events", self.parameters_changed,
                                 qos_profile_parameter_events)
        if sim_time:  # without it Foxglove's time is the messages' own (receive time)
            self.create_timer(TIME_PERIOD_S, self.broadcast_time,
                              clock=Clock(clock_type=ClockType.STEADY_TIME))
        # never stale: a graph with nothing to show is no fault of the viewer
        self.diagnostics = Diagnostics(self, silent_after_s=None)
        self.create_timer(REPORT_PERIOD_S, self.report,
                          clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.topics = RawTopics(self, self.parameters["discovery_period_s"], self.add_topic,
                                self.live_view.log, purpose="serving")
        self.report()

    def add_topic(self, topic: str, message_type: str,
                  _publishers: list[TopicEndpointInfo]) -> None:
        """A new channel of the live view; ValueError for a type it cannot describe."""
        self.live_view.add_topic(topic, message_type)

    def parameters_changed(self, event: ParameterEvent) -> None:
        """A node's new and changed parameters to the clients subscribed to them."""
        self.live_view.publish_parameters({
            parameter_name(event.node, parameter.name): plain_value(parameter.value)
            for parameter in [*event.new_parameters, *event.changed_parameters]})

    def broadcast_time(self) -> None:
        """The node's clock (simulation time) as the server's time, once /clock has run."""
        now_ns = self.get_clock().now().nanoseconds
        if now_ns > 0:
            self.live_view.broadcast_time(now_ns)

    def report(self) -> None:
        """The diagnostics status: topics served, messages forwarded, subscribed clients,
        whether clients set parameters; WARN while served off loopback."""
        message = (f"serving {len(self.live_view.channels)} topics on {self.live_view.url}"
                   + (f"; {self.exposure}" if self.exposure else ""))
        self.diagnostics.update(WARN if self.exposure else OK, message, {
            "topics": len(self.live_view.channels),
            "messages_forwarded": sum(self.live_view.counts.values()),
            "subscribed_clients": self.live_view.clients.count(),
            "parameter_set": "allowed" if self.live_view.settable else "refused",
        })

    def destroy_node(self) -> None:
        self.live_view.close()
        self.ros_parameters.close()
        counts = ", ".join(f"{topic} {count}" for topic, count in
                           sorted(self.live_view.counts.items()))
        self.get_logger().info(f"live view on {self.live_view.url} stopped: {counts}")
        super().destroy_node()


def main(args: list[str] | None = None) -> int:
    return run_node("foxglove_node", FoxgloveNode, args=args)


if __name__ == "__main__":
    sys.exit(main())
