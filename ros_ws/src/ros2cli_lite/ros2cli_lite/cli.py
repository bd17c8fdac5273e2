"""A small `ros2` command for machines without ros2cli, which no reachable registry ships.

Written by hand because neither ros2cli nor rosidl_runtime_py installs from PyPI. It covers
what this project's users need, with ros2cli's (Jazzy) output and exit statuses:

    ros2 run [--prefix CMD] PKG EXECUTABLE [ARGS...]
    ros2 pkg executables [PKG] [--full-path]
    ros2 topic list [-t] [-c] [-v] [-a] | type TOPIC | find TYPE [-c]
    ros2 topic echo TOPIC [--once] [--field F] [--timeout S] [--no-arr] [-l N | -f]
                    [--csv] [--flow-style] [--filter EXPR] [-i] [--qos-* ...]
    ros2 topic hz TOPIC [--window N] [-s | --use-sim-time] [--wall-time]
    ros2 topic bw TOPIC [--window N] [-s]
    ros2 topic info TOPIC [-v]
    ros2 topic pub [-1 | -t TIMES] [-r RATE] TOPIC TYPE [YAML]
    ros2 node list [-a] [-c]
    ros2 node info NODE
    ros2 param list [NODE] | get NODE NAME... | set NODE NAME VALUE... | dump NODE
    ros2 param describe NODE NAME... | load NODE FILE [--use-wildcard]
    ros2 service list [-t] [-c] | type SERVICE | call SERVICE TYPE [YAML] [-r HZ]
    ros2 interface show TYPE [--no-comments | --all-comments] | list [-m] [-s] [-a]
    ros2 interface package PKG
    ros2 bag info BAG

Errors end with one line on stderr and exit status 1. The pure parts (formatting) are in
render.py, the graph queries in graph.py, the topic verbs in topic.py, the parameter verbs
in param.py, the service verbs in service.py, the interface verbs in interface.py.
"""

from __future__ import annotations

import argparse
import os
import shlex
import sys
from collections.abc import Callable, Sequence

from ros2cli_lite import interface, param, service, topic
from ros2cli_lite.graph import (
    absolute_name,
    add_spin_time,
    graph_node,
    names_and_types,
    node_names,
    settle_graph,
)
from ros2cli_lite.render import (
    CliError,
    bag_info,
    field_value,
    format_document,
)

__all__ = ["CliError", "field_value", "format_document", "main", "parser"]

DEFAULT_SPIN_TIME_S = 2.0


# ------------------------------------------------------------------------ run / pkg
def executable_paths(package: str) -> list[str]:
    """The executable files under `lib/<package>` of the package's ament prefix, folders
    starting with `.` skipped, in walk order (ros2pkg's get_executable_paths)."""
    from ament_index_python.packages import PackageNotFoundError, get_package_prefix

    try:
        prefix = get_package_prefix(package)
    except (PackageNotFoundError, ValueError) as error:
        raise CliError(f"Package '{package}' not found") from error
    paths = []
    for folder, subfolders, files in os.walk(os.path.join(prefix, "lib", package)):
        subfolders[:] = sorted(name for name in subfolders if not name.startswith("."))
        paths += [path for name in sorted(files)
                  if os.access(path := os.path.join(folder, name), os.X_OK)]
    return paths


def find_executable(package: str, executable: str) -> str:
    """The package's one executable of that name, as ros2 run finds it."""
    paths = [path for path in executable_paths(package) if os.path.basename(path) == executable]
    if not paths:
        raise CliError(f"No executable found: '{executable}' in package '{package}'")
    if len(paths) > 1:
        raise CliError("Multiple executables found: " + ", ".join(paths))
    return paths[0]


def run(args: argparse.Namespace) -> int:
    """Replace this process with the executable (after the --prefix command, e.g. `time` or
    `gdb -ex run --args`, split as a shell would), so signals reach it directly."""
    path = find_executable(args.package, args.executable)
    command = [*shlex.split(args.prefix or ""), path, *args.arguments]
    try:
        os.execvp(command[0], command)
    except OSError as error:  # a prefix command that is not there
        raise CliError(f"Could not run '{command[0]}': {error.strerror}") from error
    return 1  # not reached: exec does not return


def pkg_executables(args: argparse.Namespace) -> int:
    """ros2 pkg executables [PKG]: `pkg executable` a line (--full-path: the paths), for
    the package or every package, sorted."""
    from ament_index_python.packages import get_packages_with_prefixes

    packages = [args.package_name] if args.package_name else get_packages_with_prefixes()
    for package in sorted(packages):
        for path in sorted(executable_paths(package)):
            print(path if args.full_path else f"{package} {os.path.basename(path)}")
    return 0


# --------------------------------------------------------------------------- nodes
def node_list(args: argparse.Namespace) -> int:
    """Print the fully qualified names of the nodes in the graph, hidden ones with -a; -c
    only their number (a name two nodes share counted twice, as ros2node counts)."""
    with graph_node() as node:
        settle_graph(node, args.spin_time)
        names = node_names(node, hidden=args.all)
    if args.count_nodes:
        print(len(names))
        return 0
    for name in sorted(set(names)):
        print(name)
    return 0


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


# ----------------------------------------------------------------------------- bag
def bag_info_verb(args: argparse.Namespace) -> int:
    """ros2 bag info: a recording's files, size, storage, times, messages and topics."""
    print(bag_info(args.bag_path))
    return 0


# ---------------------------------------------------------------------------- main
def parser() -> argparse.ArgumentParser:
    """The command line: `ros2 run`, `ros2 topic|node|param|interface|bag ...`."""
    root = argparse.ArgumentParser(prog="ros2", description=__doc__.splitlines()[0])
    commands = root.add_subparsers(dest="command", required=True)

    run_parser = commands.add_parser("run", help="run an executable of a package")
    run_parser.add_argument("--prefix", help="command to run it with, e.g. 'time -p'")
    run_parser.add_argument("package")
    run_parser.add_argument("executable")
    run_parser.add_argument("arguments", nargs=argparse.REMAINDER)
    run_parser.set_defaults(handler=run)
    pkg = commands.add_parser("pkg", help="inspect packages").add_subparsers(
        dest="verb", required=True
    )
    executables = pkg.add_parser("executables", help="list packages' executables")
    executables.add_argument("package_name", nargs="?")
    executables.add_argument("--full-path", action="store_true", help="print the paths")
    executables.set_defaults(handler=pkg_executables)

    node = commands.add_parser("node", help="inspect nodes").add_subparsers(
        dest="verb", required=True
    )
    nodes = node.add_parser("list", help="list the nodes")
    nodes.add_argument("-a", "--all", action="store_true", help="also hidden nodes")
    nodes.add_argument("-c", "--count-nodes", "--count", action="store_true",
                       help="print only the number of nodes")
    nodes.set_defaults(handler=node_list)
    node_info_parser = node.add_parser("info", help="a node's endpoints")
    node_info_parser.add_argument("node_name")
    node_info_parser.add_argument("--include-hidden", action="store_true")
    node_info_parser.set_defaults(handler=node_info)

    for graph_query in (nodes, node_info_parser):
        add_spin_time(graph_query, DEFAULT_SPIN_TIME_S)
    param.add_parsers(commands, DEFAULT_SPIN_TIME_S)
    service.add_parsers(commands, DEFAULT_SPIN_TIME_S)
    topic.add_parsers(commands, DEFAULT_SPIN_TIME_S)

    interface.add_parsers(commands)

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
