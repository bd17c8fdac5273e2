"""A node's health on /diagnostics: its levels and the publisher every node uses."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import rclpy.duration
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.clock import Clock, ClockType
from rclpy.node import Node

from uav_common.health import CPU_KEY, hardware_id
from uav_common.ros.messages import stamp
from uav_common.ros.qos import DIAGNOSTICS_QOS

# A node's own levels. STALE is not among them: by diagnostic_msgs' convention it is the
# aggregator's verdict on a node that has gone silent; a node without input says WARN.
OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR
# Wall time without a status update after which an input-driven node warns that its inputs
# stopped (they arrive at 2-20 Hz of sim time, and the graph runs at or above real time).
SILENT_INPUTS_S = 5.0


class Diagnostics:
    """Publishes the node's latest health on /diagnostics once a second of wall time, with
    the vehicle as hardware_id (`aircraft`, or `aircraft/uav1` in namespace /uav1) and,
    beside the node's own values, its process's CPU time so far (CPU_KEY): what the node
    costs, whatever else shares the cores.

    Published every period_s of wall time (health is for the people and tools watching the
    run), stamped in the node's time: simulation time under use_sim_time, and a clock
    source's own time (clock_s: what it publishes on /clock [s]). A node driven by inputs
    (silent_after_s given) says at least WARN, with its last status's values, once it has had
    no update for that long. A node may add statuses of its own parts (update_part:
    `<node>/<part>`, e.g. mhe_node's model_fit), published with its own. A node whose status
    is cheaper to take once per publication than per input gives before_publish, which
    calls update().
    """

    def __init__(self, node: Node, period_s: float = 1.0,
                 silent_after_s: float | None = SILENT_INPUTS_S,
                 clock_s: Callable[[], float] | None = None,
                 before_publish: Callable[[], None] | None = None) -> None:
        self._node = node
        self._before_publish = before_publish
        self._publisher = node.create_publisher(DiagnosticArray, "/diagnostics", DIAGNOSTICS_QOS)
        self._status = DiagnosticStatus(
            level=OK, name=node.get_fully_qualified_name(), message="starting",
            hardware_id=hardware_id(node.get_namespace()),
        )
        self._parts: dict[str, DiagnosticStatus] = {}
        self._silent_after_s = silent_after_s
        self._clock_s = clock_s
        self._updated_s = time.monotonic()
        node.create_timer(period_s, self.publish, clock=Clock(clock_type=ClockType.STEADY_TIME))

    def update(self, level: bytes, message: str, values: dict[str, Any]) -> None:
        """Set the status published next (level: OK, WARN or ERROR)."""
        self._status.level = level
        self._status.message = message
        self._status.values = [KeyValue(key=key, value=str(value)) for key, value in values.items()]
        self._updated_s = time.monotonic()

    def update_part(self, part: str, level: bytes, message: str, values: dict[str, Any]) -> None:
        """Set the status of one of the node's parts (named `<node>/<part>`)."""
        self._parts[part] = DiagnosticStatus(
            level=level, name=f"{self._status.name}/{part}", message=message,
            hardware_id=self._status.hardware_id,
            values=[KeyValue(key=key, value=str(value)) for key, value in values.items()])

    def publish(self) -> None:
        if self._before_publish is not None:
            self._before_publish()
        status, silent_s = self._status, time.monotonic() - self._updated_s
        level, message = status.level, status.message
        if self._silent_after_s is not None and silent_s > self._silent_after_s:
            level = max(level, WARN)  # an ERROR stays one
            message = f"no input for {silent_s:.0f} s (last: {status.message})"
        published = DiagnosticStatus(
            level=level, name=status.name, hardware_id=status.hardware_id, message=message,
            values=[*status.values, KeyValue(key=CPU_KEY, value=f"{time.process_time():.3f}")])
        array = DiagnosticArray(status=[published, *self._parts.values()])
        array.header.stamp = (self._node.get_clock().now().to_msg() if self._clock_s is None
                              else stamp(self._clock_s()))
        self._publisher.publish(array)

    def publish_last(self, timeout_s: float = 1.0) -> None:
        """Publish now and wait up to timeout_s [s] until the subscribers have it: a node
        about to end says its last status (its whole CPU time)."""
        self.publish()
        self._publisher.wait_for_all_acked(rclpy.duration.Duration(seconds=timeout_s))
