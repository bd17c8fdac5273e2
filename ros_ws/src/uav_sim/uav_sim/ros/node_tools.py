"""What every node of the project shares: QoS per kind of topic, parameters declared with
descriptors from the package's config YAML, and a /diagnostics publisher."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any, TypeVar

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.clock import Clock, ClockType
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from uav_sim.paths import default_parameters

# Sensor-rate streams and estimates: reliable and keep-all, so that a fast simulation loses
# nothing while subscribers catch up.
STREAM_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_ALL,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
# /clock: only the newest time matters.
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
DIAGNOSTICS_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


def declare_parameters(
    node: Node, package: str, config_file: str, descriptions: dict[str, str]
) -> dict[str, Any]:
    """Declare each described parameter with its default from the package's config YAML.

    Values given on the command line or in a --params-file override the defaults. Returns
    the parameters' values by name.
    """
    defaults = default_parameters(package, config_file)
    missing = set(descriptions) ^ set(defaults)
    if missing:
        raise KeyError(f"parameters without both a description and a default: {sorted(missing)}")
    for name, description in descriptions.items():
        node.declare_parameter(name, defaults[name], ParameterDescriptor(description=description))
    return {name: node.get_parameter(name).value for name in descriptions}


class Diagnostics:
    """Publishes the node's latest health on /diagnostics once a second of wall time.

    Wall time, not simulation time: health is for the people and tools watching the run.
    """

    def __init__(self, node: Node, period_s: float = 1.0) -> None:
        self._node = node
        self._publisher = node.create_publisher(DiagnosticArray, "/diagnostics", DIAGNOSTICS_QOS)
        self._status = DiagnosticStatus(
            level=OK, name=node.get_fully_qualified_name(), message="starting"
        )
        node.create_timer(period_s, self.publish, clock=Clock(clock_type=ClockType.STEADY_TIME))

    def update(self, level: bytes, message: str, values: dict[str, Any]) -> None:
        """Set the status published next (level: OK, WARN or ERROR)."""
        self._status.level = level
        self._status.message = message
        self._status.values = [KeyValue(key=key, value=str(value)) for key, value in values.items()]

    def publish(self) -> None:
        array = DiagnosticArray(status=[self._status])
        array.header.stamp = self._node.get_clock().now().to_msg()
        self._publisher.publish(array)


NodeType = TypeVar("NodeType", bound=Node)


def run_node(
    name: str,
    make_node: Callable[[], NodeType],
    run: Callable[[NodeType], None] = rclpy.spin,
    args: list[str] | None = None,
) -> int:
    """A node's main: init, make the node, run it, shut down; the exit status.

    A ValueError while making or running it (a bad parameter or scenario) ends the process
    with one line on stderr and status 1; Ctrl-C (SIGINT) or an external shutdown, with 0.
    """
    rclpy.init(args=args)
    node = None
    try:
        node = make_node()
        run(node)
        return 0
    except ValueError as error:
        print(f"{name}: {error}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, ExternalShutdownException):
        return 0
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
