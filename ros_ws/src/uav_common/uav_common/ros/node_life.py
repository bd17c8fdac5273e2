"""A node's life: its inputs subscribed once its outputs are heard, its spin, and the main
that runs it and ends it cleanly on SIGINT or SIGTERM with the project's exit statuses."""

from __future__ import annotations

import faulthandler
import re
import signal
import sys
import threading
from collections.abc import Callable
from typing import TypeVar

import rclpy
import rclpy.logging
from rclpy.clock import Clock, ClockType
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.signals import SignalHandlerOptions

from uav_common.ros.parameters import NodeArguments
from uav_common.ros_processes import STOP_TIMEOUT_S

SUBSCRIPTION_POLL_S = 0.05  # wall time between looks at an output's subscription count


def when_subscribed(node: Node, publisher: Publisher, wanted: int,
                    subscribe: Callable[[], None]) -> None:
    """Call subscribe() (the node's input subscriptions) once publisher has `wanted`
    subscriptions as the publisher itself sees them (a listener's own view of the graph can
    be ahead of the publisher's); at once when wanted is 0. The node spins meanwhile
    (parameters, diagnostics), and its source (sim_node's wait_for_subscribers) waits in
    turn for the subscriptions subscribe() makes: the whole chain is matched before the
    first message."""
    if publisher.get_subscription_count() >= wanted:
        subscribe()
        return
    node.get_logger().info(
        f"waiting for {wanted} subscription(s) of {publisher.topic_name} before subscribing")

    def look() -> None:
        if publisher.get_subscription_count() >= wanted:
            node.destroy_timer(timer)
            subscribe()

    timer = node.create_timer(SUBSCRIPTION_POLL_S, look,
                              clock=Clock(clock_type=ClockType.STEADY_TIME))


NodeType = TypeVar("NodeType", bound=Node)

# Exit statuses of a node's process.
EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
STOP_POLL_S = 0.1  # longest wait of spin() between looks at a stop signal [s, wall time]
# A node still running this long after a stop signal prints every thread's stack on stderr
# (faulthandler's own thread: it also reports a main thread stuck inside C) [s, wall time];
# before ros_processes.stop_all kills what remains.
STUCK_STOP_S = STOP_TIMEOUT_S - 2.0


class Stopped(KeyboardInterrupt):
    """SIGINT or SIGTERM arrived: the node ends, with status 0."""


class _StopRequest:
    """The stop signal received, if any, and whether the handler raises Stopped at once
    (in a node's own run loop) or only records it (in spin(), which looks between callbacks:
    raised inside a callback or a message conversion, pybind11 and the executor turn it into
    other errors)."""

    signal: int | None = None
    raises = True


def _stop(signum: int, _frame: object) -> None:
    for sig in STOP_SIGNALS:  # once is enough: the node's clean-up is not interrupted
        signal.signal(sig, signal.SIG_IGN)
    _StopRequest.signal = signum
    faulthandler.dump_traceback_later(STUCK_STOP_S, exit=False)
    if _StopRequest.raises:
        raise Stopped(signal.Signals(signum).name)


def spin(node: Node) -> None:
    """rclpy.spin until a stop signal: the wait for work ends every STOP_POLL_S to look for
    one (a Python signal handler runs only between Python statements), and a signal ends it
    between callbacks, never inside one.

    rclpy's EventsExecutor (C++, callbacks in the order their events came) rather than the
    SingleThreadedExecutor (a Python wait set rebuilt for every callback): the default demo's
    nodes took 6 / 5 / 10 ms of CPU per simulated second (detector, mhe, residual) instead
    of 11 / 7 / 15, and the graph flew at 36.6-37.2 times real time instead of 28-31
    (docs/performance.md). The nodes' timers all run on the steady clock: sim-time timers
    under an events executor are not relied on (rclcpp's lacked them, ros2/rclcpp#2457)."""
    executor = EventsExecutor()
    executor.add_node(node)
    _StopRequest.raises = False
    try:
        while executor.context.ok() and _StopRequest.signal is None:
            executor.spin_once(timeout_sec=STOP_POLL_S)
    finally:
        _StopRequest.raises = True
        executor.remove_node(node)
        executor.shutdown(timeout_sec=0.0)


def _rcl_message(error: Exception) -> str:
    """rcl's error text without its source locations (`, at /project/src/x.c:12`)."""
    text = re.sub(r", at \S+:\d+", "", str(error))
    return text.removeprefix("failed to initialize rcl: ")


def _init(name: str, args: list[str] | None) -> bool:
    """rclpy.init without rclpy's signal handlers; False, after one line, when rcl cannot
    parse the arguments (a params file that does not parse or does not exist, a bad -p)."""
    NodeArguments.given = args
    # rcl's own `Failed to parse global arguments` line would come before ours: muted.
    rclpy.logging.set_logger_level("rcl", rclpy.logging.LoggingSeverity.FATAL)
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except _rclpy.RCLError as error:
        print(f"{name}: bad ROS arguments: {_rcl_message(error)}", file=sys.stderr)
        return False
    finally:
        if rclpy.logging.get_logger_level("rcl") == rclpy.logging.LoggingSeverity.FATAL:
            rclpy.logging.set_logger_level("rcl", rclpy.logging.LoggingSeverity.UNSET)
    return True


def run_node(
    name: str,
    make_node: Callable[[], NodeType],
    run: Callable[[NodeType], None] = spin,
    args: list[str] | None = None,
) -> int:
    """A node's main: init, make the node, run it, shut down; the exit status.

    Bad input (arguments rcl cannot parse, a bad parameter or scenario: a ValueError while
    making or running the node) ends the process with one line on stderr and status 2.
    SIGINT and SIGTERM end it with status 0, however it was started: the node handles both
    itself (also a SIGINT its starter ignored, as `cmd &` in a script does), rclpy's context
    staying valid for the clean-up (rclpy's own handlers shut the context down under the
    running node: RCLError tracebacks). spin() ends between callbacks; a node's own `run`
    gets Stopped (a KeyboardInterrupt) raised in its main thread.
    """
    if threading.current_thread() is threading.main_thread():
        for sig in STOP_SIGNALS:
            signal.signal(sig, _stop)
    node = None
    try:
        if not _init(name, args):
            return EXIT_BAD_INPUT
        node = make_node()
        run(node)
        return EXIT_OK
    except (KeyboardInterrupt, ExternalShutdownException):
        return EXIT_OK
    except Exception as error:
        if _StopRequest.signal is not None:
            # an error the stop caused: Stopped raised inside a call into C++ (a message
            # conversion) comes out as another exception
            return EXIT_OK
        if isinstance(error, ValueError):
            print(f"{name}: {error}", file=sys.stderr)
            return EXIT_BAD_INPUT
        raise
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
