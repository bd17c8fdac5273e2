"""The ROS graph as the `ros2` command sees it (cli.py): a hidden node,
spinning, discovery that settles, names, topic types and a matching QoS. rclpy is imported
inside the functions, so that `ros2 --help` starts fast."""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

GRAPH_POLL_S = 0.1
# Without ros2cli's daemon every query discovers the graph afresh. A query stops once the
# graph (nodes, topics and types, services, endpoint counts) has not changed for
# SETTLE_QUIET_S and at least SETTLE_MIN_S has passed, at the latest after --spin-time.
# SETTLE_MIN_S: config/fastdds.xml makes every participant announce itself each 0.5 s, so a
# participant that missed our initial announcements answers within about 0.5 s; measured
# here (idle), the last change of the graph came 0.02-0.66 s after start, and with 0.6 s a
# loaded test run once missed a node, hence two announcement periods. SETTLE_QUIET_S: longer
# than one announcement period, so every live participant has announced itself within the
# quiet time (with 0.3 s a loaded CI run's `node list` once missed a publishing node).
# A `node list` takes 1.5-1.7 s (Python and rclpy start-up: 0.45 s).
SETTLE_MIN_S = 1.0
SETTLE_QUIET_S = 0.6
SETTLE_STEP_S = 0.02


@contextmanager
def graph_node(use_sim_time: bool = False) -> Iterator[Any]:
    """An rclpy node, hidden from `node list`, for graph queries and subscriptions."""
    import rclpy
    from rclpy.parameter import Parameter

    rclpy.init()
    node = rclpy.create_node(
        f"_ros2cli_lite_{os.getpid()}",
        start_parameter_services=False,
        enable_rosout=False,
        parameter_overrides=[Parameter("use_sim_time", value=use_sim_time)],
    )
    try:
        yield node
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def spin_for(node: Any, duration_s: float) -> None:
    """Process callbacks and discovery for `duration_s` of wall time."""
    import rclpy
    from rclpy.executors import ExternalShutdownException

    deadline = time.monotonic() + duration_s
    try:
        while (left := deadline - time.monotonic()) > 0:
            rclpy.spin_once(node, timeout_sec=min(left, GRAPH_POLL_S))
    except ExternalShutdownException as error:  # rclpy's SIGINT handler shut the context down
        raise KeyboardInterrupt from error


def graph_snapshot(node: Any) -> tuple:
    """Everything a graph query prints, to tell when discovery has settled."""
    topics = sorted((name, tuple(types)) for name, types in node.get_topic_names_and_types())
    return (
        tuple(sorted(node.get_node_names_and_namespaces())),
        tuple(topics),
        tuple(sorted(name for name, _types in node.get_service_names_and_types())),
        tuple((node.count_publishers(name), node.count_subscribers(name)) for name, _ in topics),
    )


def settle_graph(node: Any, max_s: float, ready: Callable[[], bool] = lambda: True) -> float:
    """Spin until discovery has settled (see SETTLE_MIN_S) and ready() holds, or max_s; the
    time spent."""
    started = time.monotonic()
    last, changed = None, started
    while (elapsed := time.monotonic() - started) < max_s:
        spin_for(node, SETTLE_STEP_S)
        snapshot = graph_snapshot(node)
        if snapshot != last:
            last, changed = snapshot, time.monotonic()
        elif (
            elapsed >= SETTLE_MIN_S
            and time.monotonic() - changed >= SETTLE_QUIET_S
            and ready()
        ):
            break
    return time.monotonic() - started


def absolute_name(name: str) -> str:
    """Resolve a name relative to the root namespace, as ros2cli does."""
    return name if name.startswith("/") else "/" + name


def full_name(namespace: str, name: str) -> str:
    return f"{namespace.rstrip('/')}/{name}"


def node_names(node: Any, hidden: bool = False) -> list[str]:
    """Fully qualified names of the nodes in the graph (ours is hidden)."""
    return [
        full_name(namespace, name)
        for name, namespace in node.get_node_names_and_namespaces()
        if hidden or not name.startswith("_")
    ]


def service_names(node: Any) -> set[str]:
    return {name for name, _types in node.get_service_names_and_types()}


def names_and_types(entries: list, hidden: bool) -> list:
    """Sorted (name, types) pairs without hidden names (a part starting with `_`, such as
    an action's `_action/...` endpoints) unless asked, as ros2node filters them."""
    from rclpy.topic_or_service_is_hidden import topic_or_service_is_hidden

    return sorted(
        (name, types) for name, types in entries
        if hidden or not topic_or_service_is_hidden(name)
    )


def print_listing(entries: list, count: bool, show_types: bool) -> None:
    """A graph listing as ros2cli prints it: only the number of entries (-c), or a name a
    line, with `[types]` when asked (-t)."""
    if count:
        print(len(entries))
    for name, types in [] if count else entries:
        print(f"{name} [{', '.join(types)}]" if show_types else name)


def print_types(kind: str, name: str, max_s: float) -> int:
    """`ros2 topic|service type NAME` (kind `topic` or `service`): the types one a line,
    once discovery has settled or the name has appeared; an error if it did not."""
    from ros2cli_lite.render import CliError

    with graph_node() as node:
        query = (node.get_topic_names_and_types if kind == "topic"
                 else node.get_service_names_and_types)
        settle_graph(node, max_s, ready=lambda: name in dict(query()))
        types = dict(query()).get(name)
    if not types:
        raise CliError(f"Unknown {kind} '{name}'")
    print(*types, sep="\n")
    return 0


def add_spin_time(verb: Any, default_s: float, *aliases: str) -> None:
    """A graph query's --spin-time [s] (and aliases): the longest wait for discovery."""
    verb.add_argument(
        "--spin-time", *aliases, type=float, default=default_s, dest="spin_time",
        help="longest time to wait for discovery to settle [s]",
    )


def topic_types(node: Any) -> dict[str, list[str]]:
    """Every topic in the graph with its type names."""
    return dict(node.get_topic_names_and_types())


def wait_for_topic_type(node: Any, topic: str, deadline: float | None) -> str | None:
    """Type name of `topic`, waiting until some publisher announces it; None at the deadline."""
    announced = False
    warn_at = time.monotonic() + SETTLE_MIN_S  # not before discovery had its chance
    while True:
        types = topic_types(node).get(topic)
        if types:
            return types[0]
        if deadline is not None and time.monotonic() >= deadline:
            return None
        if not announced and time.monotonic() >= warn_at:
            print(f"WARNING: topic [{topic}] does not appear to be published yet", file=sys.stderr)
            announced = True
        spin_for(node, GRAPH_POLL_S)


def subscription_qos(node: Any, topic: str, base: Any = None) -> Any:
    """`base` (default: depth 10) made to match every publisher of `topic`: reliable only if
    all of them are, transient-local only if all of them are (ros2cli's choice for echo)."""
    import copy

    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    publishers = node.get_publishers_info_by_topic(topic)
    reliable = bool(publishers) and all(
        info.qos_profile.reliability == ReliabilityPolicy.RELIABLE for info in publishers
    )
    transient = bool(publishers) and all(
        info.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for info in publishers
    )
    profile = QoSProfile(depth=10) if base is None else copy.copy(base)
    profile.reliability = ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT
    profile.durability = (
        DurabilityPolicy.TRANSIENT_LOCAL if transient else DurabilityPolicy.VOLATILE
    )
    return profile
