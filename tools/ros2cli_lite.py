"""A small `ros2` command for machines without ros2cli, which no reachable registry ships.

Written by hand because neither ros2cli nor rosidl_runtime_py installs from PyPI. It covers
what this project's users need, with output shaped like ros2cli's:

    ros2 run PKG EXECUTABLE [ARGS...]
    ros2 topic list [-t]
    ros2 topic echo TOPIC [--once] [--field F] [--timeout S]
    ros2 topic hz TOPIC [--window N]
    ros2 topic info TOPIC
    ros2 node list [-a]

Errors end with one line on stderr and exit status 1.
"""

from __future__ import annotations

import argparse
import importlib
import itertools
import math
import os
import statistics
import sys
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import yaml

GRAPH_POLL_S = 0.1
# Without ros2cli's daemon every query discovers the graph afresh: with config/fastdds.xml
# that took 0.06 to 1.0 s here (14 trials).
DEFAULT_SPIN_TIME_S = 2.0


class CliError(Exception):
    """A user-facing error: its text is printed as one line, the exit status is 1."""


# ----------------------------------------------------------------------------- run
def find_executable(package: str, executable: str) -> str:
    """Path of `lib/<package>/<executable>` in the package's ament prefix, as ros2 run finds it."""
    from ament_index_python.packages import PackageNotFoundError, get_package_prefix

    try:
        prefix = get_package_prefix(package)
    except (PackageNotFoundError, ValueError) as error:
        raise CliError(f"Package '{package}' not found") from error
    path = os.path.join(prefix, "lib", package, executable)
    if not (os.path.isfile(path) and os.access(path, os.X_OK)):
        raise CliError(f"No executable found: '{executable}' in package '{package}'")
    return path


def run(args: argparse.Namespace) -> int:
    """Replace this process with the executable, so signals reach it directly."""
    path = find_executable(args.package, args.executable)
    os.execv(path, [path, *args.arguments])
    return 1  # not reached: execv does not return


# --------------------------------------------------------------------------- graph
@contextmanager
def graph_node() -> Iterator[Any]:
    """An rclpy node, hidden from `node list`, for graph queries and subscriptions."""
    import rclpy

    rclpy.init()
    node = rclpy.create_node(
        f"_ros2cli_lite_{os.getpid()}", start_parameter_services=False, enable_rosout=False
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


def absolute_name(name: str) -> str:
    """Resolve a name relative to the root namespace, as ros2cli does."""
    return name if name.startswith("/") else "/" + name


def topic_types(node: Any) -> dict[str, list[str]]:
    """Every topic in the graph with its type names."""
    return dict(node.get_topic_names_and_types())


def wait_for_topic_type(node: Any, topic: str, deadline: float | None) -> str | None:
    """Type name of `topic`, waiting until some publisher announces it; None at the deadline."""
    announced = False
    while True:
        types = topic_types(node).get(topic)
        if types:
            return types[0]
        if deadline is not None and time.monotonic() >= deadline:
            return None
        if not announced:
            print(f"WARNING: topic [{topic}] does not appear to be published yet", file=sys.stderr)
            announced = True
        spin_for(node, GRAPH_POLL_S)


def message_class(type_name: str) -> type:
    """Import a message class from its name `pkg/msg/Type`."""
    package, kind, name = type_name.split("/")
    try:
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ImportError, AttributeError) as error:
        raise CliError(f"The message type '{type_name}' is invalid or not built") from error


def subscription_qos(node: Any, topic: str) -> Any:
    """A QoS that matches every publisher of `topic` (ros2cli's choice for echo and hz)."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    publishers = node.get_publishers_info_by_topic(topic)
    reliable = bool(publishers) and all(
        info.qos_profile.reliability == ReliabilityPolicy.RELIABLE for info in publishers
    )
    transient = bool(publishers) and all(
        info.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for info in publishers
    )
    return QoSProfile(
        depth=10,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if transient else DurabilityPolicy.VOLATILE,
    )


# ---------------------------------------------------------------------------- echo
def to_plain(value: Any) -> Any:
    """A message, array or scalar as plain Python data, fields in declaration order."""
    if hasattr(value, "get_fields_and_field_types"):
        fields = value.get_fields_and_field_types()
        return {field: to_plain(getattr(value, field)) for field in fields}
    if hasattr(value, "tolist"):  # numpy arrays and scalars of fixed-size array fields
        return value.tolist()
    if isinstance(value, list | tuple):
        return [to_plain(item) for item in value]
    return value


def field_value(message: Any, field_path: str | None) -> Any:
    """The value at a dotted field path (`header.stamp.sec`) of a message."""
    value = message
    for part in field_path.split(".") if field_path else ():
        if not hasattr(value, "get_fields_and_field_types") or not hasattr(value, part):
            raise CliError(f"Invalid field '{field_path}': no field '{part}'")
        value = getattr(value, part)
    return value


def format_document(value: Any) -> str:
    """One YAML document as ros2 topic echo prints it, ending with the `---` separator."""
    plain = to_plain(value)
    if isinstance(plain, dict | list):
        text = yaml.safe_dump(plain, sort_keys=False, default_flow_style=False, width=10**9)
    else:
        text = f"{plain}\n"
    return text + "---"


def echo(args: argparse.Namespace) -> int:
    """Print every message of a topic (or the first, with --once) as YAML documents."""
    topic = absolute_name(args.topic)
    deadline = None if args.timeout is None else time.monotonic() + args.timeout
    received: list[Any] = []
    timed_out = CliError(f"no message received on [{topic}] within {args.timeout} s")
    with graph_node() as node:
        type_name = wait_for_topic_type(node, topic, deadline)
        if type_name is None:
            raise timed_out
        message_type = message_class(type_name)

        def on_message(message: Any) -> None:
            if args.once and received:
                return
            received.append(message)
            print(format_document(field_value(message, args.field)), flush=True)

        node.create_subscription(message_type, topic, on_message, subscription_qos(node, topic))
        while not (args.once and received):
            if deadline is not None and time.monotonic() >= deadline:
                raise timed_out
            spin_for(node, GRAPH_POLL_S)
    return 0


# ------------------------------------------------------------------------------ hz
def rate_report(arrivals_s: Sequence[float]) -> str:
    """ros2 topic hz's report for a window of arrival times (seconds, increasing)."""
    periods = [later - earlier for earlier, later in itertools.pairwise(arrivals_s)]
    mean_s = statistics.fmean(periods)
    return (
        f"average rate: {1.0 / mean_s:.3f}\n"
        f"\tmin: {min(periods):.3f}s max: {max(periods):.3f}s "
        f"std dev: {statistics.pstdev(periods):.5f}s window: {len(arrivals_s)}"
    )


def hz(args: argparse.Namespace) -> int:
    """Print the receive rate of a topic about once a second, until interrupted."""
    topic = absolute_name(args.topic)
    arrivals_s: deque[float] = deque(maxlen=args.window)
    with graph_node() as node:
        type_name = wait_for_topic_type(node, topic, deadline=None)
        assert type_name is not None  # no deadline: it waits until the topic appears
        message_type = message_class(type_name)
        node.create_subscription(
            message_type,
            topic,
            lambda _message: arrivals_s.append(time.monotonic()),
            subscription_qos(node, topic),
            raw=True,  # only the arrival time matters: skip deserialisation
        )
        while True:
            spin_for(node, 1.0)
            if len(arrivals_s) >= 2 and not math.isclose(arrivals_s[0], arrivals_s[-1]):
                print(rate_report(list(arrivals_s)), flush=True)
            else:
                print("no new messages", flush=True)


# --------------------------------------------------------------------- list / info
def topic_list(args: argparse.Namespace) -> int:
    """Print the topics in the graph, sorted, with their types when asked."""
    with graph_node() as node:
        spin_for(node, args.spin_time)
        for name, types in sorted(topic_types(node).items()):
            print(f"{name} [{', '.join(types)}]" if args.show_types else name)
    return 0


def topic_info(args: argparse.Namespace) -> int:
    """Print a topic's type and how many publishers and subscriptions it has."""
    topic = absolute_name(args.topic)
    with graph_node() as node:
        spin_for(node, args.spin_time)
        types = topic_types(node).get(topic)
        if not types:
            raise CliError(f"Unknown topic '{topic}'")
        print(f"Type: {', '.join(types)}")
        print(f"Publisher count: {node.count_publishers(topic)}")
        # Our own node subscribes to nothing here, so every subscription is someone else's.
        print(f"Subscription count: {node.count_subscribers(topic)}")
    return 0


def node_list(args: argparse.Namespace) -> int:
    """Print the fully qualified names of the nodes in the graph, hidden ones with -a."""
    with graph_node() as node:
        spin_for(node, args.spin_time)
        names = {
            f"{namespace.rstrip('/')}/{name}"
            for name, namespace in node.get_node_names_and_namespaces()
            if args.all or not name.startswith("_")
        }
    for name in sorted(names):
        print(name)
    return 0


# ---------------------------------------------------------------------------- main
def parser() -> argparse.ArgumentParser:
    """The command line: `ros2 run`, `ros2 topic ...`, `ros2 node list`."""
    root = argparse.ArgumentParser(prog="ros2", description=__doc__.splitlines()[0])
    commands = root.add_subparsers(dest="command", required=True)

    run_parser = commands.add_parser("run", help="run an executable of a package")
    run_parser.add_argument("package")
    run_parser.add_argument("executable")
    run_parser.add_argument("arguments", nargs=argparse.REMAINDER)
    run_parser.set_defaults(handler=run)

    topic = commands.add_parser("topic", help="inspect topics").add_subparsers(
        dest="verb", required=True
    )
    listing = topic.add_parser("list", help="list the topics")
    listing.add_argument("-t", "--show-types", action="store_true")
    listing.set_defaults(handler=topic_list)
    echo_parser = topic.add_parser("echo", help="print the messages of a topic")
    echo_parser.add_argument("topic")
    echo_parser.add_argument("--once", action="store_true", help="print one message and exit")
    echo_parser.add_argument("--field", help="print only this dotted field, e.g. header.stamp")
    echo_parser.add_argument(
        "--timeout", type=float, help="seconds to wait for the topic and its first message"
    )
    echo_parser.set_defaults(handler=echo)
    hz_parser = topic.add_parser("hz", help="print the receive rate of a topic")
    hz_parser.add_argument("topic")
    hz_parser.add_argument("-w", "--window", type=int, default=10000)
    hz_parser.set_defaults(handler=hz)
    info = topic.add_parser("info", help="print a topic's type and endpoint counts")
    info.add_argument("topic")
    info.set_defaults(handler=topic_info)

    node = commands.add_parser("node", help="inspect nodes").add_subparsers(
        dest="verb", required=True
    )
    nodes = node.add_parser("list", help="list the nodes")
    nodes.add_argument("-a", "--all", action="store_true", help="also hidden nodes")
    nodes.set_defaults(handler=node_list)

    for graph_query in (listing, info, nodes):
        graph_query.add_argument(
            "--spin-time", type=float, default=DEFAULT_SPIN_TIME_S, help="discovery time [s]"
        )
    return root


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: dispatch, and turn errors and Ctrl-C into one line and a status."""
    args = parser().parse_args(argv)
    handler: Callable[[argparse.Namespace], int] = args.handler
    try:
        return handler(args)
    except CliError as error:
        print(error, file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 0
