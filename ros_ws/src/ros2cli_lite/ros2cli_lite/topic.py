"""`ros2 topic list/echo/hz/bw/info/type/find/pub` with ros2topic's (Jazzy) options, output
and exit statuses."""

from __future__ import annotations

import argparse
import copy
import time
from collections.abc import Callable
from typing import Any

import yaml

from ros2cli_lite.graph import (
    GRAPH_POLL_S,
    absolute_name,
    add_spin_time,
    graph_node,
    names_and_types,
    print_listing,
    print_types,
    settle_graph,
    spin_for,
    subscription_qos,
    topic_types,
    wait_for_topic_type,
)
from ros2cli_lite.render import (
    DEFAULT_TRUNCATE_LENGTH,
    BandwidthWindow,
    CliError,
    RateWindow,
    field_value,
    format_csv,
    format_document,
    is_message,
    message_class,
    set_message_fields,
)

DEFAULT_BW_WINDOW = 100  # messages, ros2topic bw's default
ECHO_QOS_PROFILE = "sensor_data"  # ros2topic echo's preset


# ---------------------------------------------------------------------------- list
def topic_list(args: argparse.Namespace) -> int:
    """`ros2 topic list`: names sorted (`-t` with `[types]`), `-c` only their number, `-v`
    the published and the subscribed ones with their endpoint counts, as ros2topic prints."""
    with graph_node() as node:
        settle_graph(node, args.spin_time)
        topics = names_and_types(node.get_topic_names_and_types(), args.include_hidden_topics)
        # Counted with the others: our own hidden node's /parameter_events publisher.
        counts = {name: (node.count_publishers(name), node.count_subscribers(name))
                  for name, _types in topics}
    if args.verbose and not args.count_topics:
        for title, kind, side in (("Published", "publisher", 0), ("Subscribed", "subscriber", 1)):
            print(f"{title} topics:")
            for name, types in topics:
                if count := counts[name][side]:
                    print(f" * {name} [{', '.join(types)}] {count} {kind}"
                          + ("s" if count > 1 else ""))
            print()
    else:
        print_listing(topics, args.count_topics, args.show_types)
    return 0


def topic_type(args: argparse.Namespace) -> int:
    """`ros2 topic type TOPIC`: its type(s), one a line; status 1 for a topic not seen."""
    return print_types("topic", absolute_name(args.topic), args.spin_time)


def topic_find(args: argparse.Namespace) -> int:
    """`ros2 topic find TYPE`: the topics of that type (`pkg/msg/Name`), `-c` their number."""
    with graph_node() as node:
        settle_graph(node, args.spin_time)
        topics = names_and_types(node.get_topic_names_and_types(), args.include_hidden_topics)
    found = [(name, types) for name, types in topics if args.topic_type in types]
    print_listing(found, args.count_topics, show_types=False)
    return 0


# ---------------------------------------------------------------------------- echo
def echo_qos(node: Any, topic: str, args: argparse.Namespace) -> Any:
    """The subscription's QoS as ros2topic echo chooses it: the --qos-profile preset with the
    --qos-* overrides when any is given, else the preset made to match the publishers."""
    from rclpy.qos import (
        DurabilityPolicy,
        HistoryPolicy,
        QoSPresetProfiles,
        ReliabilityPolicy,
    )

    preset = copy.copy(QoSPresetProfiles.get_from_short_key(args.qos_profile))
    overrides = (args.qos_depth, args.qos_history, args.qos_reliability, args.qos_durability)
    if all(value is None for value in overrides):
        return subscription_qos(node, topic, preset)
    if args.qos_history:
        preset.history = HistoryPolicy.get_from_short_key(args.qos_history)
    if args.qos_reliability:
        preset.reliability = ReliabilityPolicy.get_from_short_key(args.qos_reliability)
    if args.qos_durability:
        preset.durability = DurabilityPolicy.get_from_short_key(args.qos_durability)
    if args.qos_depth is not None and args.qos_depth >= 0:
        preset.depth = args.qos_depth
    elif preset.durability == DurabilityPolicy.TRANSIENT_LOCAL and preset.depth == 0:
        preset.depth = 1  # ros2cli's guard: a late-joiner needs room for one sample
    return preset


def message_filter(expression: str | None) -> Callable[[Any], bool]:
    """--filter: a Python expression of `m` (the message, or the --field value) that keeps a
    message when true, evaluated as ros2topic does (builtins available)."""
    if not expression:
        return lambda _m: True
    try:
        code = compile(expression, "--filter", "eval")
    except SyntaxError as error:
        raise CliError(f"Invalid filter expression '{expression}': {error.msg}") from error

    def keep(m: Any) -> bool:
        try:
            return bool(eval(code, {}, {"m": m}))
        except Exception as error:  # whatever the user's expression raises ends the echo
            raise CliError(f"Filter expression '{expression}' failed: {error!r}") from error

    return keep


def echo_text(value: Any, info: dict, args: argparse.Namespace) -> str:
    """What ros2topic echo prints for one (field) value: a YAML document, or with --csv one
    line; -i adds the message info (timestamps, sequence numbers) before it."""
    options = {
        "truncate_length": None if args.full_length else args.truncate_length,
        "no_arr": args.no_arr,
        "no_str": args.no_str,
    }
    if args.csv and is_message(value):  # a --field leaf is printed as YAML either way
        line = format_csv(value, **options)
        if args.include_message_info:
            line = ",".join(str(x) for x in info.values()) + "," + line
        return line
    document = format_document(value, flow_style=args.flow_style, **options)
    return f"{yaml.dump(info)}---\n{document}" if args.include_message_info else document


def echo(args: argparse.Namespace) -> int:
    """Print every message of a topic (or the first, with --once) as YAML documents or CSV.

    --timeout as ros2cli Jazzy (ros2topic/verb/echo.py): a timer of that length ends the
    echo with status 0 and no message, whether or not anything arrived, with or without
    --once. Jazzy fails at once (status 1, "Could not determine the type for the passed
    topic") for a topic nobody publishes; this stand-in waits for it instead, up to the
    timeout, and then fails with status 1 and one line. --filter skips the messages it
    rejects (they do not end --once).
    """
    topic = absolute_name(args.topic)
    started = time.monotonic()
    deadline = None if args.timeout is None else started + args.timeout
    keep = message_filter(args.filter_expr)
    printed = 0
    with graph_node() as node:
        type_name = wait_for_topic_type(node, topic, deadline)
        if type_name is None:
            raise CliError(f"Could not determine the type for the passed topic [{topic}] "
                           f"within {args.timeout} s")
        message_type = message_class(type_name)
        failures: list[CliError] = []

        def on_message(message: Any, info: dict) -> None:
            nonlocal printed
            if (args.once and printed) or failures:
                return
            try:
                value = field_value(message, args.field)
                if keep(value):
                    printed += 1
                    print(echo_text(value, dict(info), args), flush=True)
            except CliError as error:  # raised out of the executor it would be lost
                failures.append(error)

        node.create_subscription(message_type, topic, on_message, echo_qos(node, topic, args))
        while not (args.once and printed):
            if failures:
                raise failures[0]
            if deadline is not None and time.monotonic() >= deadline:
                return 0
            spin_for(node, GRAPH_POLL_S)
    return 0


# ------------------------------------------------------------------------------ bw
def bw(args: argparse.Namespace) -> int:
    """`ros2 topic bw TOPIC`: each second, the bandwidth of the last --window messages and
    their sizes (serialised, as received), until interrupted; as ros2topic bw, with the
    sensor-data QoS, on wall time or with -s on /clock."""
    from rclpy.qos import qos_profile_sensor_data

    topic = absolute_name(args.topic)
    window = BandwidthWindow(args.window)
    with graph_node(use_sim_time=args.use_sim_time) as node:
        clock = node.get_clock()

        def now_s() -> float:
            return clock.now().nanoseconds * 1e-9 if args.use_sim_time else time.monotonic()

        type_name = wait_for_topic_type(node, topic, deadline=None)
        assert type_name is not None  # no deadline: it waits until the topic appears
        node.create_subscription(
            message_class(type_name), topic, lambda data: window.add(now_s(), len(data)),
            qos_profile_sensor_data, raw=True,  # the serialised size is what is measured
        )
        print(f"Subscribed to [{topic}]", flush=True)
        while True:
            spin_for(node, 1.0)
            if (report := window.report(now_s())) is not None:
                print(report, flush=True)


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


# --------------------------------------------------------------------------- info
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



# -------------------------------------------------------------------------- parser
def positive_float(text: str) -> float:
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError("value must be positive")
    return value


def positive_int(text: str) -> int:
    value = int(text)
    if value <= 0:
        raise argparse.ArgumentTypeError("value must be a positive integer")
    return value


def add_qos_arguments(verb: argparse.ArgumentParser, default_profile: str) -> None:
    """ros2topic's --qos-* options: a preset and overrides of its depth and policies."""
    from rclpy.qos import (
        DurabilityPolicy,
        HistoryPolicy,
        QoSPresetProfiles,
        ReliabilityPolicy,
    )

    verb.add_argument("--qos-profile", choices=QoSPresetProfiles.short_keys(),
                      default=default_profile,
                      help=f"QoS preset to subscribe with (default: {default_profile})")
    verb.add_argument("--qos-depth", metavar="N", type=int,
                      help="queue size (overrides the preset)")
    for name, policy in (("history", HistoryPolicy), ("reliability", ReliabilityPolicy),
                         ("durability", DurabilityPolicy)):
        verb.add_argument(f"--qos-{name}", choices=policy.short_keys(),
                          help=f"{name} policy (overrides the preset)")


def add_parsers(commands: Any, spin_time_s: float) -> None:
    """`ros2 topic list|find|type|echo|bw|hz|info|pub` on the top-level subparsers."""
    topic = commands.add_parser("topic", help="inspect topics").add_subparsers(
        dest="verb", required=True
    )
    listing = topic.add_parser("list", help="list the topics")
    listing.add_argument("-t", "--show-types", action="store_true")
    listing.add_argument("-c", "--count-topics", "--count", action="store_true",
                         help="print only the number of topics")
    listing.add_argument("-v", "--verbose", action="store_true",
                         help="published and subscribed topics with their endpoint counts")
    listing.set_defaults(handler=topic_list)
    find = topic.add_parser("find", help="list the topics of a type")
    find.add_argument("topic_type", help="e.g. uav_fault_msgs/msg/FaultAlarm")
    find.add_argument("-c", "--count-topics", action="store_true")
    find.set_defaults(handler=topic_find)
    for hideable in (listing, find):
        hideable.add_argument("-a", "--all", "--include-hidden-topics", action="store_true",
                              dest="include_hidden_topics", help="also hidden topics")
    kind = topic.add_parser("type", help="print a topic's type")
    kind.add_argument("topic")
    kind.set_defaults(handler=topic_type)
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
    echo_parser.add_argument("--csv", action="store_true", help="one comma-separated line each")
    echo_parser.add_argument("--flow-style", action="store_true",
                             help="collections in YAML's flow style")
    echo_parser.add_argument("--filter", dest="filter_expr",
                             help="print only messages m for which this Python expression holds")
    echo_parser.add_argument("-i", "--include-message-info", action="store_true",
                             help="also the message info (timestamps, sequence numbers)")
    add_qos_arguments(echo_parser, ECHO_QOS_PROFILE)
    echo_parser.set_defaults(handler=echo)
    bw_parser = topic.add_parser("bw", help="print the bandwidth a topic uses")
    bw_parser.add_argument("topic")
    bw_parser.add_argument("-w", "--window", type=positive_int, default=DEFAULT_BW_WINDOW,
                           help=f"messages in the window (default: {DEFAULT_BW_WINDOW})")
    bw_parser.add_argument("-s", "--use-sim-time", action="store_true", help="time on /clock")
    bw_parser.set_defaults(handler=bw)
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
    for graph_query in (listing, find, kind, info):
        add_spin_time(graph_query, spin_time_s)

