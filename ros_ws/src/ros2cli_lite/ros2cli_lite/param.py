"""`ros2 param list/get/set/dump/load/describe` through a node's standard parameter services
(rcl_interfaces/srv ListParameters, GetParameters, SetParameters, DescribeParameters), with
ros2param's (Jazzy) output and exit statuses: "Node not found" and the other errors are one
line on stderr and status 1; a refused `set` or `load` prints "Setting parameter failed:
<reason>" (`load`: "Set parameter NAME failed: <reason>") on stderr with status 0, as
ros2param does.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

import yaml

from ros2cli_lite.graph import (
    add_spin_time,
    graph_node,
    node_names,
    service_names,
    settle_graph,
)
from ros2cli_lite.render import CliError

SERVICE_WAIT_S = 5.0
CALL_TIMEOUT_S = 10.0
# ParameterType numbers to ros2param's type names (ros2param.api.get_parameter_type_string).
TYPE_NAMES = {
    0: "not set", 1: "boolean", 2: "integer", 3: "double", 4: "string", 5: "byte array",
    6: "boolean array", 7: "integer array", 8: "double array", 9: "string array",
}
# ros2 param get's label for each ParameterType and the ParameterValue field it prints.
GET_LABELS = {
    1: ("Boolean value is:", "bool_value"),
    2: ("Integer value is:", "integer_value"),
    3: ("Double value is:", "double_value"),
    4: ("String value is:", "string_value"),
    5: ("Byte values are:", "byte_array_value"),
    6: ("Boolean values are:", "bool_array_value"),
    7: ("Integer values are:", "integer_array_value"),
    8: ("Double values are:", "double_array_value"),
    9: ("String values are:", "string_array_value"),
}


# ----------------------------------------------------------------------------- pure
def get_line(value: Any, hide_type: bool = False) -> str:
    """What ros2 param get prints for a ParameterValue (arrays as Python prints them, e.g.
    `Double values are: array('d', [0.5, 0.5])`, as ros2param does)."""
    if value.type == 0:
        return "None" if hide_type else "Parameter not set."
    if value.type not in GET_LABELS:
        raise CliError(f"Unknown parameter type '{value.type}'")
    label, field = GET_LABELS[value.type]
    shown = getattr(value, field)
    return f"{shown}" if hide_type else f"{label} {shown}"


def plain_value(value: Any) -> Any:
    """A ParameterValue as plain data for YAML (ros2param.api.get_value)."""
    if value.type == 0:
        return None
    shown = getattr(value, GET_LABELS[value.type][1])
    return list(shown) if value.type >= 5 else shown


def dump_text(node_name: str, names: list[str], values: list[Any]) -> str:
    """ros2 param dump's YAML: names split at '.' into nested mappings, keys sorted."""
    parameters: dict[str, Any] = {}
    for name, value in zip(names, values, strict=True):
        *parents, leaf = name.split(".")
        level = parameters
        for parent in parents:
            level = level.setdefault(parent, {})
        level[leaf] = plain_value(value)
    return yaml.dump({node_name: {"ros__parameters": parameters}}, default_flow_style=False)


# ------------------------------------------------------------------------------ ROS
def absolute_node_name(name: str) -> str:
    return name if name.startswith("/") else "/" + name


def wait_for_node(node: Any, name: str, timeout_s: float) -> None:
    """Wait until the node is in the graph (ros2node's wait_for_node), else 'Node not found'."""

    settle_graph(node, timeout_s, ready=lambda: name in node_names(node, hidden=True))
    if name not in node_names(node, hidden=True):
        raise CliError("Node not found")


def call(node: Any, service_type: Any, node_name: str, service: str, request: Any) -> Any:
    """Call one of the node's parameter services and return the response."""
    import rclpy

    client = node.create_client(service_type, f"{node_name}/{service}")
    try:
        if not client.wait_for_service(timeout_sec=SERVICE_WAIT_S):
            raise CliError(
                "Wait for service timed out waiting for parameter services for node "
                f"{node_name}"
            )
        future = client.call_async(request)
        rclpy.spin_until_future_complete(node, future, timeout_sec=CALL_TIMEOUT_S)
        if future.result() is None:
            raise CliError(
                f"Exception while calling service of node '{node_name}': {future.exception()}"
            )
        return future.result()
    finally:
        node.destroy_client(client)


def list_names(node: Any, node_name: str, prefixes: list[str]) -> list[str]:
    from rcl_interfaces.srv import ListParameters

    request = ListParameters.Request(prefixes=prefixes)
    response = call(node, ListParameters, node_name, "list_parameters", request)
    return sorted(response.result.names)


def get_values(node: Any, node_name: str, names: list[str]) -> list[Any]:
    from rcl_interfaces.srv import GetParameters

    request = GetParameters.Request(names=names)
    return list(call(node, GetParameters, node_name, "get_parameters", request).values)


def param_list(args: argparse.Namespace) -> int:
    """`ros2 param list [NODE]`: names, indented, under each node's name when none is given."""
    from rcl_interfaces.srv import DescribeParameters

    with graph_node() as node:
        if args.node_name:
            target = absolute_node_name(args.node_name)
            wait_for_node(node, target, args.spin_time)
            targets = [target]
        else:
            settle_graph(node, args.spin_time)
            services = service_names(node)
            targets = [
                name for name in sorted(node_names(node, hidden=args.include_hidden_nodes))
                if f"{name}/list_parameters" in services
            ]
        for target in targets:
            names = list_names(node, target, args.param_prefixes)
            if not args.node_name:
                print(f"{target}:")
            types = {}
            if args.param_type:
                request = DescribeParameters.Request(names=names)
                response = call(node, DescribeParameters, target, "describe_parameters", request)
                types = {d.name: TYPE_NAMES.get(d.type, "unknown") for d in response.descriptors}
            for name in names:
                print(f"  {name} (type: {types[name]})" if args.param_type else f"  {name}")
    return 0


def param_get(args: argparse.Namespace) -> int:
    """`ros2 param get NODE NAME...`: `Double value is: 4.0`; with several names each line
    starts `NAME: `, as ros2param's set does for several pairs; an undeclared name is an
    error."""
    target = absolute_node_name(args.node_name)
    with graph_node() as node:
        wait_for_node(node, target, args.spin_time)
        values = get_values(node, target, args.parameter_names)
    if not values:
        raise CliError("Parameter not set")
    several = len(args.parameter_names) > 1
    for name, value in zip(args.parameter_names, values, strict=True):
        line = get_line(value, args.hide_type)
        print(f"{name}: {line}" if several else line)
    return 0


def print_set_results(results: list[Any], names: list[str], success: str, failure: str) -> None:
    """One line per SetParametersResult, in ros2param's words: `success[: reason]` on stdout,
    `failure[: reason]` on stderr; `{name}` in the words is the parameter's name."""
    for name, result in zip(names, results, strict=True):
        words = (success if result.successful else failure).format(name=name)
        line = words + (f": {result.reason}" if result.reason else "")
        print(line, file=sys.stdout if result.successful else sys.stderr)


def set_parameters(node: Any, target: str, parameters: list[Any]) -> list[Any]:
    """The node's SetParametersResult for each parameter (rcl_interfaces/msg/Parameter)."""
    from rcl_interfaces.srv import SetParameters

    request = SetParameters.Request(parameters=parameters)
    return list(call(node, SetParameters, target, "set_parameters", request).results)


def param_set(args: argparse.Namespace) -> int:
    """`ros2 param set NODE NAME VALUE [NAME VALUE ...]`: each value parsed as YAML (rclpy's
    get_parameter_value); prints the node's answers in ros2param's words (`NAME: ` first when
    several), status 0 either way."""
    from rcl_interfaces.msg import Parameter
    from rclpy.parameter import get_parameter_value

    words = args.params_and_values
    if len(words) % 2:
        raise CliError("Parameters must be provided as name/value pairs: name value "
                       f"[name value ...]. Got {len(words)} argument(s).")
    names = words[::2]
    parameters = [
        Parameter(name=name, value=get_parameter_value(text))
        for name, text in zip(names, words[1::2], strict=True)
    ]
    target = absolute_node_name(args.node_name)
    with graph_node() as node:
        wait_for_node(node, target, args.spin_time)
        results = set_parameters(node, target, parameters)
    prefix = "{name}: " if len(names) > 1 else ""
    print_set_results(results, names, prefix + "Set parameter successful",
                      prefix + "Setting parameter failed")
    return 0


def param_load(args: argparse.Namespace) -> int:
    """`ros2 param load NODE FILE [--use-wildcard]`: every node section of the parameters file
    (and `/**` with --use-wildcard), as ros2param loads it; `Set parameter NAME successful`
    or, on stderr, `Set parameter NAME failed: reason` for each; status 0 either way."""
    from rclpy.parameter import parameter_dict_from_yaml_file

    try:
        parameters = list(
            parameter_dict_from_yaml_file(args.parameter_file, args.use_wildcard).values()
        )
    except (OSError, RuntimeError, yaml.YAMLError, AttributeError) as error:
        raise CliError(str(error)) from error
    target = absolute_node_name(args.node_name)
    with graph_node() as node:
        wait_for_node(node, target, args.spin_time)
        results = set_parameters(node, target, parameters)
    names = [parameter.name for parameter in parameters]
    print_set_results(results, names, "Set parameter {name} successful",
                      "Set parameter {name} failed")
    return 0


def describe_lines(descriptor: Any) -> list[str]:
    """ros2 param describe's lines for one ParameterDescriptor."""
    lines = [f"Parameter name: {descriptor.name}",
             f"  Type: {TYPE_NAMES.get(descriptor.type, 'unknown')}"]
    if descriptor.description:
        lines.append(f"  Description: {descriptor.description}")
    lines.append("  Constraints:")
    if descriptor.read_only:
        lines.append("    Read only: true")
    ranges = [*descriptor.floating_point_range, *descriptor.integer_range]
    if ranges:
        lines += [f"    Min value: {ranges[0].from_value}", f"    Max value: {ranges[0].to_value}"]
        if ranges[0].step:
            lines.append(f"    Step: {ranges[0].step}")
    if descriptor.additional_constraints:
        lines.append(f"    Additional constraints: {descriptor.additional_constraints}")
    return lines


def param_describe(args: argparse.Namespace) -> int:
    """`ros2 param describe NODE NAME...`: type, description and constraints of each."""
    from rcl_interfaces.srv import DescribeParameters

    target = absolute_node_name(args.node_name)
    with graph_node() as node:
        wait_for_node(node, target, args.spin_time)
        request = DescribeParameters.Request(names=args.parameter_names)
        response = call(node, DescribeParameters, target, "describe_parameters", request)
    for descriptor in response.descriptors:
        print(*describe_lines(descriptor), sep="\n")
    return 0


def param_dump(args: argparse.Namespace) -> int:
    """`ros2 param dump NODE`: the node's parameters as a parameters file, on stdout."""

    target = absolute_node_name(args.node_name)
    with graph_node() as node:
        wait_for_node(node, target, args.spin_time)
        names = list_names(node, target, [])
        values = get_values(node, target, names)
    print(dump_text(target, names, values))
    return 0


def add_parsers(commands: Any, spin_time_s: float) -> None:
    """`ros2 param list|get|set|dump|load|describe` on the top-level subparsers."""
    param = commands.add_parser("param", help="inspect and set node parameters")
    verbs = param.add_subparsers(dest="verb", required=True)
    listing = verbs.add_parser("list", help="list a node's (or every node's) parameters")
    listing.add_argument("node_name", nargs="?")
    listing.add_argument("--include-hidden-nodes", action="store_true")
    listing.add_argument("--param-prefixes", nargs="+", default=[])
    listing.add_argument("--param-type", action="store_true", help="print the types too")
    listing.set_defaults(handler=param_list)
    get = verbs.add_parser("get", help="print parameters' values")
    get.add_argument("node_name")
    get.add_argument("parameter_names", nargs="+", metavar="parameter_name")
    get.add_argument("--hide-type", action="store_true")
    get.set_defaults(handler=param_get)
    set_parser = verbs.add_parser("set", help="set parameters (the values are YAML)")
    set_parser.add_argument("node_name")
    set_parser.add_argument("params_and_values", nargs="+", metavar="name value")
    set_parser.set_defaults(handler=param_set)
    dump = verbs.add_parser("dump", help="print a node's parameters as YAML")
    dump.add_argument("node_name")
    dump.set_defaults(handler=param_dump)
    load = verbs.add_parser("load", help="set a node's parameters from a parameters file")
    load.add_argument("node_name")
    load.add_argument("parameter_file")
    load.add_argument("--use-wildcard", action="store_true",
                      help="also load the file's '/**' parameters")
    load.set_defaults(handler=param_load)
    describe = verbs.add_parser("describe", help="parameters' types and constraints")
    describe.add_argument("node_name")
    describe.add_argument("parameter_names", nargs="+", metavar="parameter_name")
    describe.set_defaults(handler=param_describe)
    for verb in (listing, get, set_parser, dump, load, describe):
        add_spin_time(verb, spin_time_s, "--timeout")
