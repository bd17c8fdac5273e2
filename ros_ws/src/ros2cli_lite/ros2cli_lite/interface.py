"""`ros2 interface show/list/package` with ros2interface's (Jazzy) output, from the ament
index (`rosidl_interfaces` resources) and the definition files in the packages' share folders.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ros2cli_lite.render import CliError

KINDS = ("msg", "srv", "action")
SECTIONS = {"msg": "Messages", "srv": "Services", "action": "Actions"}
SEPARATORS = ("---",)  # between a service's request and response, an action's parts


def interfaces(package: str) -> list[str]:
    """`kind/Name` of every interface of a package, sorted (one `.idl` file each)."""
    from ament_index_python import get_resource, has_resource

    if not has_resource("packages", package):
        raise CliError(f"Unknown package '{package}'")
    if not has_resource("rosidl_interfaces", package):
        return []
    content, _prefix = get_resource("rosidl_interfaces", package)
    return sorted(
        line.removesuffix(".idl") for line in content.splitlines()
        if line.endswith(".idl") and line.split("/")[0] in KINDS
    )


def full_type_name(type_name: str) -> str:
    """`pkg/kind/Name`; the short `pkg/Name` resolved to the first of msg, srv and action
    that the package installs."""
    parts = type_name.split("/")
    if len(parts) == 2:
        package, name = parts
        for kind in KINDS:
            if f"{kind}/{name}" in interfaces(package):
                return f"{package}/{kind}/{name}"
        raise CliError(f"Could not find the interface '{type_name}'")
    if len(parts) != 3:
        raise CliError(f"Invalid name '{type_name}'. Expected three parts separated by '/'")
    return type_name


def interface_path(type_name: str) -> Path:
    """The definition file of `pkg/kind/Name` in the package's share folder."""
    from ament_index_python.packages import PackageNotFoundError, get_package_share_directory

    package, kind, name = type_name.split("/")
    try:
        share = Path(get_package_share_directory(package))
    except (PackageNotFoundError, ValueError) as error:
        raise CliError(f"Unknown package '{package}'") from error
    path = share / kind / f"{name}.{kind}"
    if not path.is_file():
        raise CliError(f"Could not find the interface '{path}'")
    return path


def without_comment(text: str) -> str:
    """A definition line up to its `#` comment, right-stripped: a `#` inside a quoted
    string constant's value does not start one."""
    quote = None
    for index, char in enumerate(text):
        if quote:
            quote = None if char == quote else quote
        elif char in "\"'":
            quote = char
        elif char == "#":
            return text[:index].rstrip()
    return text.rstrip()


def interface_lines(
    type_name: str, comments: bool = True, nested_comments: bool = False, indent: int = 0
) -> Iterator[str]:
    """ros2 interface show's lines: the file as written (without comments and blank lines
    unless `comments`), each nested message type expanded below its field one tab deeper
    with `nested_comments` (ros2interface's show.py, on rosidl_adapter's parser)."""
    from rosidl_adapter.parser import parse_message_string

    full_name = full_type_name(type_name)
    package, _, name = full_name.split("/")
    for raw in interface_path(full_name).read_text().splitlines():
        text = raw.rstrip() if comments else without_comment(raw)
        if not comments and not text:
            continue
        yield f"{indent * chr(9)}{text}" if text else ""
        if text in SEPARATORS:
            continue
        fields = parse_message_string(package, name, without_comment(raw)).fields
        if fields and "/" in str(fields[0].type):
            nested = str(fields[0].type).split("[")[0]
            yield from interface_lines(
                nested.replace("/", "/msg/"), nested_comments, nested_comments, indent + 1
            )


def interface_show(args: argparse.Namespace) -> int:
    """ros2 interface show: the definition, nested types expanded one tab deeper."""
    comments = args.all_comments or not args.no_comments
    for line in interface_lines(args.type, comments, args.all_comments):
        print(line)
    return 0


def chosen_kinds(args: argparse.Namespace) -> list[str]:
    """The kinds -m, -s and -a ask for; all three when none is given."""
    asked = [kind for kind, flag in zip(KINDS, (args.only_msgs, args.only_srvs,
                                                args.only_actions), strict=True) if flag]
    return asked or list(KINDS)


def interface_list(args: argparse.Namespace) -> int:
    """ros2 interface list: `Messages:`, `Services:`, `Actions:`, each with its types
    `    pkg/kind/Name`, packages and names sorted."""
    from ament_index_python import get_resources

    every = {package: interfaces(package) for package in sorted(get_resources("rosidl_interfaces"))}
    for kind in chosen_kinds(args):
        print(f"{SECTIONS[kind]}:")
        for package, names in every.items():
            for name in names:
                if name.startswith(f"{kind}/"):
                    print(f"    {package}/{name}")
    return 0


def interface_package(args: argparse.Namespace) -> int:
    """ros2 interface package PKG: its types, `pkg/kind/Name` a line."""
    kinds = chosen_kinds(args)
    for name in interfaces(args.package_name):
        if name.split("/")[0] in kinds:
            print(f"{args.package_name}/{name}")
    return 0


def add_parsers(commands: Any) -> None:
    """`ros2 interface show|list|package` on the top-level subparsers."""
    verbs = commands.add_parser("interface", help="interface definitions").add_subparsers(
        dest="verb", required=True
    )
    show = verbs.add_parser("show", help="print a type's definition")
    show.add_argument("type", help="pkg/msg/Name (srv, action), or pkg/Name")
    comments = show.add_mutually_exclusive_group()
    comments.add_argument("--all-comments", action="store_true")
    comments.add_argument("--no-comments", action="store_true")
    show.set_defaults(handler=interface_show)
    listing = verbs.add_parser("list", help="list every installed type")
    listing.set_defaults(handler=interface_list)
    package = verbs.add_parser("package", help="list a package's types")
    package.add_argument("package_name")
    package.set_defaults(handler=interface_package)
    for verb in (listing, package):
        verb.add_argument("-m", "--only-msgs", action="store_true", help="only messages")
        verb.add_argument("-s", "--only-srvs", action="store_true", help="only services")
        verb.add_argument("-a", "--only-actions", action="store_true", help="only actions")
