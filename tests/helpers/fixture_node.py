"""The main of a test fixture process: one node calling a tick function on a wall-clock
timer until interrupted."""

from __future__ import annotations

from collections.abc import Callable

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node


def run_timer_node(name: str, period_s: float,
                   make_tick: Callable[[Node], Callable[[], None]]) -> None:
    """Create the node, give it make_tick(node) as a timer callback every period_s [s] of
    wall time, and spin until SIGINT or shutdown."""
    rclpy.init()
    node = rclpy.create_node(name)
    node.create_timer(period_s, make_tick(node))
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
