"""A small `ros2` command for machines without ros2cli, which no reachable registry ships.

Written by hand because neither ros2cli nor rosidl_runtime_py installs from PyPI. It covers
what this project's users need, with ros2cli's (Jazzy) output and exit statuses:

    ros2 run PKG EXECUTABLE [ARGS...]
    ros2 topic list [-t]
    ros2 topic echo TOPIC [--once] [--field F] [--timeout S] [--no-arr] [-l N | -f]
    ros2 topic hz TOPIC [--window N] [-s | --use-sim-time] [--wall-time]
    ros2 topic info TOPIC [-v]
    ros2 topic pub [-1 | -t TIMES] [-r RATE] TOPIC TYPE [YAML]
    ros2 node list [-a]
    ros2 node info NODE
    ros2 param list [NODE] | get NODE NAME... | set NODE NAME VALUE... | dump NODE
    ros2 param describe NODE NAME... | load NODE FILE [--use-wildcard]
    ros2 service list [-t] [-c] | type SERVICE | call SERVICE TYPE [YAML] [-r HZ]
    ros2 interface show TYPE
    ros2 bag info BAG

Errors end with one line on stderr and exit status 1. The pure parts (formatting) are in
ros2cli_render.py, the graph queries in ros2cli_graph.py, the parameter verbs in
ros2cli_param.py, the service verbs in ros2cli_service.py.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable, Sequence
from typing import Any

import ros2cli_param
import ros2cli_service
import yaml
from ros2cli_graph import (
    GRAPH_POLL_S,
    absolute_name,
    graph_node,
    node_names,
    settle_graph,
    spin_for,
    subscription_qos,
    topic_types,
    wait_for_topic_type,
)
from ros2cli_render import (
    DEFAULT_TRUNCATE_LENGTH,
    CliError,
    RateWindow,
    bag_info,
    field_value,
    format_document,
    interface_lines,
    message_class,
    set_message_fields,
)

__all__ = ["CliError", "field_value", "format_document", "main", "parser"]

DEFAULT_SPIN_TIME_S = 2.0


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


# ---------------------------------------------------------------------------- echo
def echo(args: argparse.Namespace) -> int:
    """Print every message of a topic (or the first, with --once) as YAML documents.

    --timeout as ros2cli Jazzy (ros2topic/verb/echo.py): a timer of that length ends the
    echo with status 0 and no message, whether or not anything arrived, with or without
    --once. Jazzy fails at once (status 1, "Could not determine the type for the passed
    topic") for a topic nobody publishes; this stand-in waits for it instead, up to the
    timeout, and then fails with status 1 and one line.
    """
    topic = absolute_name(args.topic)
    started = time.monotonic()
    deadline = None if args.timeout is None else started + args.timeout
    received: list[Any] = []
    options = {
        "truncate_length": None if args.full_length else args.truncate_length,
        "no_arr": args.no_arr,
        "no_str": args.no_str,
    }
    with graph_node() as node:
        type_name = wait_for_topic_type(node, topic, deadline)
        if type_name is None:
            raise CliError(f"Could not determine the type for the passed topic [{topic}] "
                           f"within {args.timeout} s")
        message_type = message_class(type_name)

        def on_message(message: Any) -> None:
            if args.once and received:
                return
            received.append(message)
            print(format_document(field_value(message, args.field), **options), flush=True)

        node.create_subscription(message_type, topic, on_message, subscription_qos(node, topic))
        while not (args.once and received):
            if deadline is not None and time.monotonic() >= deadline:
                return 0
            spin_for(node, GRAPH_POLL_S)
    return 0


# ------------------------------------------------------------------------------ hz
def hz(args: argparse.Namespace) -> int:
    """Print the receive rate of a topic once a second of the chosen clock, until interrupted.

    As ros2cli Jazzy (ros2topic/verb/hz.py): arrivals are timed on the node's ROS clock,
    which is wall time unless --use-sim-time (-s) makes it follow /clock; --wall-time forces
    wall time. ros2cli never switches to /clock by itself, and neither does this.
    """
    from rclpy.clock import Clock, ClockType

    topic = absolute_name(args.topic)
    window = RateWindow(args.window)
    use_sim_time = args.use_sim_time and not args.wall_time
    with graph_node(use_sim_time=use_sim_time) as node:
        clock = node.get_clock() if use_sim_time else Clock(clock_type=ClockType.SYSTEM_TIME)
        type_name = wait_for_topic_type(node, topic, deadline=None)
        assert type_name is not None  # no deadline: it waits until the topic appears
        message_type = message_class(type_name)

        def on_message(_message: Any) -> None:
            if (reset := window.add(clock.now().nanoseconds)) is not None:
                print(reset, flush=True)
            if (report := window.report()) is not None:
                print(report, flush=True)

        node.create_subscription(
            message_type, topic, on_message, subscription_qos(node, topic),
            raw=True,  # only the arrival time matters: skip deserialisation
        )
        while True:
            spin_for(node, 1.0)


# ----------------------------------------------------------------------------- pub
def pub(args: argparse.Namespace) -> int:
    """Publish a message built from YAML, as ros2 topic pub (Jazzy) does: `publisher:
    beginning loop`, then `publishing #N: <repr>` and a blank line per message; with --once
    or --times it first waits for a matching subscription (-w) and lingers --keep-alive s."""
    import rclpy
    from rclpy.qos import QoSProfile

    message_type = message_class(args.message_type)
    values = yaml.safe_load(args.values)
    if not isinstance(values, dict):
        raise CliError("The passed value needs to be a dictionary in YAML format")
    times = 1 if args.once else args.times
    wait_for = args.wait_matching_subscriptions
    if wait_for is None:
        wait_for = 1 if times else 0
    with graph_node() as node:
        publisher = node.create_publisher(
            message_type, absolute_name(args.topic), QoSProfile(depth=10)
        )
        message = message_type()
        try:
            set_message_fields(message, values, lambda: node.get_clock().now().to_msg())
        except Exception as error:  # ros2cli reports whatever failed
            raise CliError(f"Failed to populate field: {error}") from error
        waited = 0
        while publisher.get_subscription_count() < wait_for:
            if waited % 10 == 0:
                print(f"Waiting for at least {wait_for} matching subscription(s)...", flush=True)
            waited += 1
            spin_for(node, 0.1)
        print("publisher: beginning loop", flush=True)
        count = 0

        def publish() -> None:
            nonlocal count
            count += 1
            if args.print and count % args.print == 0:
                print(f"publishing #{count}: {message!r}\n", flush=True)
            publisher.publish(message)

        publish()
        timer = node.create_timer(1.0 / args.rate, publish)
        while times == 0 or count < times:
            rclpy.spin_once(node, timeout_sec=GRAPH_POLL_S)
        node.destroy_timer(timer)
        spin_for(node, args.keep_alive)  # let a reliable message reach its readers
    return 0


# --------------------------------------------------------------------- list / info
def topic_list(args: argparse.Namespace) -> int:
    """Print the topics in the graph, sorted, with their types when asked."""
    with graph_node() as node:
        settle_graph(node, args.spin_time)
        for name, types in sorted(topic_types(node).items()):
            print(f"{name} [{', '.join(types)}]" if args.show_types else name)
    return 0


def topic_info(args: argparse.Namespace) -> int:
    """Print a topic's type and endpoint counts; -v: every endpoint, as rclpy's
    TopicEndpointInfo prints itself (node, namespace, type, type hash, endpoint type, GID,
    QoS), each followed by a blank line as ros2cli does."""
    topic = absolute_name(args.topic)
    end = "\n\n" if args.verbose else "\n"
    with graph_node() as node:
        settle_graph(node, args.spin_time, ready=lambda: topic in topic_types(node))
        types = topic_types(node).get(topic)
        if not types:
            raise CliError(f"Unknown topic '{topic}'")
        print(f"Type: {types[0] if len(types) == 1 else types}", end=end)
        print(f"Publisher count: {node.count_publishers(topic)}", end=end)
        if args.verbose:
            for info in node.get_publishers_info_by_topic(topic):
                print(info, end=end)
        # Our own node subscribes to nothing here, so every subscription is someone else's.
        print(f"Subscription count: {node.count_subscribers(topic)}", end=end)
        if args.verbose:
            for info in node.get_subscriptions_info_by_topic(topic):
                print(info, end=end)
    return 0


def node_list(args: argparse.Namespace) -> int:
    """Print the fully qualified names of the nodes in the graph, hidden ones with -a."""
    with graph_node() as node:
        settle_graph(node, args.spin_time)
        names = set(node_names(node, hidden=args.all))
    for name in sorted(names):
        print(name)
    return 0


def names_and_types(entries: list, hidden: bool) -> list:
    """Sorted (name, types) pairs without hidden names (a part starting with `_`, such as
    an action's `_action/...` endpoints) unless asked, as ros2node filters them."""
    from rclpy.topic_or_service_is_hidden import topic_or_service_is_hidden

    return sorted(
        (name, types) for name, types in entries
        if hidden or not topic_or_service_is_hidden(name)
    )


def node_info(args: argparse.Namespace) -> int:
    """ros2 node info: the node's name, then its subscribers, publishers, service servers and
    clients and action servers and clients, `    name: type` each, an empty section as an
    empty line (ros2cli prints an empty list that way)."""
    from rclpy.action import (
        get_action_client_names_and_types_by_node,
        get_action_server_names_and_types_by_node,
    )

    target = absolute_name(args.node_name)
    with graph_node() as node:
        settle_graph(node, args.spin_time, ready=lambda: target in node_names(node, True))
        count = node_names(node, hidden=True).count(target)
        if count == 0:
            raise CliError(f"Unable to find node '{args.node_name}'")
        if count > 1:
            print(f"There are {count} nodes in the graph with the exact name "
                  f'"{args.node_name}". You are seeing information about only one of them.',
                  file=sys.stderr)
        namespace, _, name = target.rpartition("/")
        namespace = namespace or "/"
        hidden = args.include_hidden
        by_node = (name, namespace)
        sections = [
            (title, names_and_types(query(*by_node), hidden))
            for title, query in (
                ("Subscribers", node.get_subscriber_names_and_types_by_node),
                ("Publishers", node.get_publisher_names_and_types_by_node),
                ("Service Servers", node.get_service_names_and_types_by_node),
                ("Service Clients", node.get_client_names_and_types_by_node),
            )
        ]
        sections += [
            ("Action Servers", names_and_types(
                get_action_server_names_and_types_by_node(node, *by_node), hidden)),
            ("Action Clients", names_and_types(
                get_action_client_names_and_types_by_node(node, *by_node), hidden)),
        ]
    print(args.node_name)
    for title, entries in sections:
        print(f"  {title}:")
        print(*[f"    {name}: {', '.join(types)}" for name, types in entries], sep="\n")
    return 0


# ------------------------------------------------------------------ interface / bag
def interface_show(args: argparse.Namespace) -> int:
    """ros2 interface show: the definition, nested types expanded one tab deeper."""
    comments = args.all_comments or not args.no_comments
    for line in interface_lines(args.type, comments, args.all_comments):
        print(line)
    return 0


def bag_info_verb(args: argparse.Namespace) -> int:
    """ros2 bag info: a recording's files, size, storage, times, messages and topics."""
    print(bag_info(args.bag_path))
    return 0


# ---------------------------------------------------------------------------- main
def positive_float(text: str) -> float:
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError("value must be positive")
    return value


def parser() -> argparse.ArgumentParser:
    """The command line: `ros2 run`, `ros2 topic|node|param|interface|bag ...`."""
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
        "--timeout", type=positive_float, help="end after this many seconds (status 0)"
    )
    echo_parser.add_argument("--no-arr", action="store_true", help="don't print array fields")
    echo_parser.add_argument("--no-str", action="store_true", help="don't print string fields")
    echo_parser.add_argument(
        "--truncate-length", "-l", type=int, default=DEFAULT_TRUNCATE_LENGTH,
        help=f"truncate arrays, bytes and strings to this length (default: "
             f"{DEFAULT_TRUNCATE_LENGTH})",
    )
    echo_parser.add_argument("--full-length", "-f", action="store_true", help="never truncate")
    echo_parser.set_defaults(handler=echo)
    hz_parser = topic.add_parser("hz", help="print the receive rate of a topic")
    hz_parser.add_argument("topic")
    hz_parser.add_argument("-w", "--window", type=int, default=10000)
    hz_parser.add_argument(
        "-s", "--use-sim-time", action="store_true", help="time arrivals on /clock"
    )
    hz_parser.add_argument("--wall-time", action="store_true", help="time arrivals on wall time")
    hz_parser.set_defaults(handler=hz)
    info = topic.add_parser("info", help="print a topic's type and endpoints")
    info.add_argument("topic")
    info.add_argument("-v", "--verbose", action="store_true", help="every endpoint and its QoS")
    info.set_defaults(handler=topic_info)
    pub_parser = topic.add_parser("pub", help="publish a message")
    pub_parser.add_argument("topic")
    pub_parser.add_argument("message_type")
    pub_parser.add_argument("values", nargs="?", default="{}")
    pub_parser.add_argument("-r", "--rate", type=positive_float, default=1.0)
    pub_parser.add_argument("-p", "--print", type=int, default=1, help="print every N-th")
    once_or_times = pub_parser.add_mutually_exclusive_group()
    once_or_times.add_argument("-1", "--once", action="store_true")
    once_or_times.add_argument("-t", "--times", type=int, default=0)
    pub_parser.add_argument("-w", "--wait-matching-subscriptions", type=int, default=None)
    pub_parser.add_argument("--keep-alive", type=positive_float, default=0.1)
    pub_parser.set_defaults(handler=pub)

    node = commands.add_parser("node", help="inspect nodes").add_subparsers(
        dest="verb", required=True
    )
    nodes = node.add_parser("list", help="list the nodes")
    nodes.add_argument("-a", "--all", action="store_true", help="also hidden nodes")
    nodes.set_defaults(handler=node_list)
    node_info_parser = node.add_parser("info", help="a node's endpoints")
    node_info_parser.add_argument("node_name")
    node_info_parser.add_argument("--include-hidden", action="store_true")
    node_info_parser.set_defaults(handler=node_info)

    for graph_query in (listing, info, nodes, node_info_parser):
        graph_query.add_argument(
            "--spin-time", type=float, default=DEFAULT_SPIN_TIME_S,
            help="longest time to wait for discovery to settle [s]",
        )
    ros2cli_param.add_parsers(commands, DEFAULT_SPIN_TIME_S)
    ros2cli_service.add_parsers(commands, DEFAULT_SPIN_TIME_S)

    interface = commands.add_parser("interface", help="show interface definitions")
    show = interface.add_subparsers(dest="verb", required=True).add_parser("show")
    show.add_argument("type")
    comments = show.add_mutually_exclusive_group()
    comments.add_argument("--all-comments", action="store_true")
    comments.add_argument("--no-comments", action="store_true")
    show.set_defaults(handler=interface_show)

    bag = commands.add_parser("bag", help="inspect rosbag2 recordings")
    bag_info_parser = bag.add_subparsers(dest="verb", required=True).add_parser("info")
    bag_info_parser.add_argument("bag_path")
    bag_info_parser.set_defaults(handler=bag_info_verb)
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
    except BrokenPipeError:  # `ros2 ... | head`: the reader has what it wanted
        sys.stderr.close()
        return 0
