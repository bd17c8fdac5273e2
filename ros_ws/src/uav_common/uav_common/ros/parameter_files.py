"""Which parameters a node was given only by a parameter file's wildcard section.

ROS users write one parameter file for every node, the shared keys under `/**:`; rclpy hands
each node every key of such a section, meant for it or not. A node takes what it has and
ignores the rest of a wildcard section (declare_parameters says so in one warning line);
keys in a section named for the node, or given with `-p`, stay strict. rclpy keeps no
record of where an override came from, so the files are read again here from the
process's ROS arguments (`--ros-args ... --params-file FILE ... -p NAME:=VALUE ... --`).
No rclpy.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import yaml

WILDCARD_SECTIONS = ("/**", "**")
ROS_ARGS_START, ROS_ARGS_END = "--ros-args", "--"
PARAMS_FILE_FLAG = "--params-file"
PARAM_FLAGS = ("-p", "--param")


def ros_argument_pairs(argv: Sequence[str]) -> list[tuple[str, str]]:
    """(flag, value) of each flag with a value inside argv's --ros-args spans."""
    pairs, inside = [], False
    for index, argument in enumerate(argv):
        if argument == ROS_ARGS_START:
            inside = True
        elif argument == ROS_ARGS_END:
            inside = False
        elif inside and index + 1 < len(argv) and argument in (PARAMS_FILE_FLAG, *PARAM_FLAGS):
            pairs.append((argument, argv[index + 1]))
    return pairs


def flattened_names(parameters: Mapping[str, Any], prefix: str = "") -> set[str]:
    """The parameter names of a ros__parameters mapping, nested keys joined by dots."""
    names = set()
    for key, value in parameters.items():
        name = f"{prefix}{key}"
        names |= flattened_names(value, f"{name}.") if isinstance(value, Mapping) else {name}
    return names


def names_for_node(section: str, node_name: str) -> bool:
    """Whether a parameter file's section names the node (`mhe_node`, `/uav1/mhe_node`)."""
    return section.rstrip("/").split("/")[-1] == node_name


def wildcard_only_names(argv: Sequence[str], node_name: str) -> set[str]:
    """Names given to node_name by a wildcard section of a --params-file in argv and by no
    section naming the node nor a -p. A file that cannot be read is rcl's to refuse: none
    of its names counts here."""
    wildcard, named = set(), set()
    for flag, value in ros_argument_pairs(argv):
        if flag in PARAM_FLAGS:
            named.add(value.split(":=", 1)[0])
            continue
        try:
            sections = yaml.safe_load(Path(value).read_text())
        except (OSError, yaml.YAMLError):
            continue
        for section, body in (sections or {}).items() if isinstance(sections, dict) else ():
            parameters = body.get("ros__parameters") if isinstance(body, dict) else None
            if not isinstance(parameters, Mapping):
                continue
            if section in WILDCARD_SECTIONS:
                wildcard |= flattened_names(parameters)
            elif names_for_node(str(section), node_name):
                named |= flattened_names(parameters)
    return wildcard - named
