"""`ros2 service list/type/call` with ros2service's (Jazzy) output and exit statuses:
`list [-t] [-c]` one name a line (types in brackets), `type` the type(s) or status 1,
`call` "requester: making request: <repr>" and "response:\n<repr>", each followed by a blank
line, repeated at `-r` Hz until interrupted.
"""

from __future__ import annotations

import argparse
import importlib
import time
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
)
from ros2cli_lite.render import CliError, set_message_fields


def service_class(type_name: str) -> Any:
    """The service class of `pkg/srv/Name` or `pkg/Name` (ros2service accepts both)."""
    parts = type_name.split("/")
    if len(parts) == 2:
        parts = [parts[0], "srv", parts[1]]
    try:
        service = getattr(importlib.import_module(".".join(parts[:-1])), parts[-1])
    except (AttributeError, ImportError, ValueError) as error:
        raise CliError("The passed service type is invalid") from error
    if not (hasattr(service, "Request") and hasattr(service, "Response")):
        raise CliError("The passed type is not a service")
    return service


def service_list(args: argparse.Namespace) -> int:
    """`ros2 service list`: names, `-t` with `[types]`, `-c` only their number."""
    with graph_node() as node:
        settle_graph(node, args.spin_time)
        services = names_and_types(
            node.get_service_names_and_types(), args.include_hidden_services
        )
    print_listing(services, args.count_services, args.show_types)
    return 0


def service_type(args: argparse.Namespace) -> int:
    """`ros2 service type NAME`: one type a line; status 1 for a service not in the graph."""
    return print_types("service", absolute_name(args.service_name), args.spin_time)


def service_call(args: argparse.Namespace) -> int:
    """`ros2 service call NAME TYPE [YAML] [-r HZ]`: one call, or one every 1/HZ s."""
    if args.rate is not None and args.rate <= 0:
        raise CliError("rate must be greater than zero")
    service = service_class(args.service_type)
    values = yaml.safe_load(args.values)
    with graph_node() as node:
        request = service.Request()
        try:
            set_message_fields(request, values or {}, lambda: node.get_clock().now().to_msg())
        except Exception as error:  # ros2service reports whatever failed, as this does
            raise CliError(f"Failed to populate field: {error}") from error
        client = node.create_client(service, absolute_name(args.service_name))
        if not client.service_is_ready():
            print("waiting for service to become available...", flush=True)
            client.wait_for_service()  # as ros2service: until it comes, or Ctrl-C
        while True:
            print(f"requester: making request: {request!r}\n", flush=True)
            last_call = time.monotonic()
            future = client.call_async(request)
            while not future.done():
                spin_for(node, GRAPH_POLL_S)
            if future.result() is None:
                raise CliError(f"Exception while calling service: {future.exception()!r}")
            print(f"response:\n{future.result()!r}\n", flush=True)
            if args.rate is None:
                return 0
            spin_for(node, max(0.0, last_call + 1.0 / args.rate - time.monotonic()))


def add_parsers(commands: Any, spin_time_s: float) -> None:
    """`ros2 service list|type|call` on the top-level subparsers."""
    verbs = commands.add_parser("service", help="inspect and call services").add_subparsers(
        dest="verb", required=True
    )
    listing = verbs.add_parser("list", help="list the services")
    listing.add_argument("-t", "--show-types", action="store_true")
    listing.add_argument("-c", "--count-services", action="store_true",
                         help="print only the number of services")
    listing.set_defaults(handler=service_list)
    kind = verbs.add_parser("type", help="print a service's type")
    kind.add_argument("service_name")
    kind.set_defaults(handler=service_type)
    for graph_query in (listing, kind):
        graph_query.add_argument("--include-hidden-services", action="store_true")
        add_spin_time(graph_query, spin_time_s)
    call = verbs.add_parser("call", help="call a service")
    call.add_argument("service_name")
    call.add_argument("service_type", help="e.g. rcl_interfaces/srv/GetParameters")
    call.add_argument("values", nargs="?", default="{}", help="the request in YAML")
    call.add_argument("-r", "--rate", type=float, help="repeat the call at this rate [Hz]")
    call.set_defaults(handler=service_call)

