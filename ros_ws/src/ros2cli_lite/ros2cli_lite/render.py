"""Pure parts of the project's `ros2` command: no ROS graph, so unit-testable.

Messages as ros2cli's YAML (rosidl_runtime_py.message_to_yaml: truncation, --no-arr), YAML
values into messages (set_message_fields, for `topic pub`), CSV lines (`topic echo --csv`),
the receive-rate window of `topic hz` (ros2topic's ROSTopicHz), the bandwidth window of
`topic bw` and rosbag2 metadata (`bag info`, rosbag2_py's format_bag_meta_data).
"""

from __future__ import annotations

import array
import importlib
import math
import os
import sys
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml

DEFAULT_TRUNCATE_LENGTH = 128  # ros2topic echo's default; --full-length lifts it


class CliError(Exception):
    """A user-facing error: its text is printed as one line, the exit status is 1."""


# ------------------------------------------------------------------- messages as YAML
def _type_name(value_type: Any) -> str:
    from rosidl_parser import definition

    if isinstance(value_type, definition.BasicType):
        return value_type.typename
    if isinstance(value_type, definition.AbstractString):
        return "string"
    if isinstance(value_type, definition.AbstractWString):
        return "wstring"
    if isinstance(value_type, definition.NamespacedType):
        return "/".join(value_type.namespaced_name())
    return "unknown"


def abbreviated_array(value: Any, field_type: Any) -> str:
    """What --no-arr prints in place of an array field (rosidl_runtime_py's wording)."""
    from rosidl_parser import definition

    name = _type_name(field_type.value_type)
    if isinstance(field_type, definition.Array):
        return f"<array type: {name}[{field_type.size}]>"
    if isinstance(field_type, definition.BoundedSequence):
        return f"<sequence type: {name}[{field_type.maximum_size}], length: {len(value)}>"
    if isinstance(field_type, definition.UnboundedSequence):
        return f"<sequence type: {name}, length: {len(value)}>"
    return "unknown"


def is_message(value: Any) -> bool:
    return hasattr(value, "get_fields_and_field_types")


def to_plain(
    value: Any,
    field_type: Any = None,
    truncate_length: int | None = None,
    no_arr: bool = False,
    no_str: bool = False,
) -> Any:
    """A message, array or scalar as plain data, fields in declaration order, truncated and
    abbreviated as rosidl_runtime_py's message_to_ordereddict does for ros2 topic echo."""
    import numpy  # here, not at the top: `ros2 run` and the graph verbs never need it

    options = {"truncate_length": truncate_length, "no_arr": no_arr, "no_str": no_str}
    if is_message(value):
        names = value.get_fields_and_field_types()
        return {
            name: to_plain(getattr(value, name), slot, **options)
            for name, slot in zip(names, value.SLOT_TYPES, strict=True)
        }
    if isinstance(value, bytes):
        text = "".join(chr(c) for c in value)
        too_long = truncate_length is not None and len(value) > truncate_length
        return text[:truncate_length] + "..." if too_long else text
    if isinstance(value, str):
        if no_str:
            return f"<string length: <{len(value)}>>"
        if truncate_length is not None and len(value) > truncate_length:
            return value[:truncate_length] + "..."
        return value
    if isinstance(value, numpy.generic):  # numpy scalars of fixed-size array fields
        return value.item()
    if isinstance(value, list | tuple | array.array | numpy.ndarray):
        if no_arr and field_type is not None:
            return abbreviated_array(value, field_type)
        items = [to_plain(item, **options) for item in list(value)[:truncate_length]]
        too_long = truncate_length is not None and len(value) > truncate_length
        return [*items, "..."] if too_long else items
    return value


def field_value(message: Any, field_path: str | None) -> Any:
    """The value at a dotted field path (`header.stamp.sec`) of a message."""
    value = message
    for part in field_path.split(".") if field_path else ():
        if not is_message(value) or not hasattr(value, part):
            raise CliError(f"Invalid field '{field_path}': no field '{part}'")
        value = getattr(value, part)
    return value


def format_document(value: Any, flow_style: bool = False, **options: Any) -> str:
    """One YAML document as ros2 topic echo prints it, ending with the `---` separator;
    flow_style: collections in flow style (`{a: 1, b: [2, 3]}`), as echo's --flow-style."""
    plain = to_plain(value, **options)
    if isinstance(plain, dict | list):
        text = yaml.safe_dump(
            plain, sort_keys=False, default_flow_style=flow_style, width=sys.maxsize,
            allow_unicode=True,
        )
    else:
        text = f"{plain}\n"
    return text + "---"


def format_csv(
    value: Any,
    field_type: Any = None,
    truncate_length: int | None = None,
    no_arr: bool = False,
    no_str: bool = False,
) -> str:
    """A message as one line of comma-separated values, every field recursively in order,
    as rosidl_runtime_py's message_to_csv prints it for ros2 topic echo --csv: an array
    cut after truncate_length elements with `...`, a string or bytes after truncate_length
    characters with `...` appended."""
    import numpy

    options = {"truncate_length": truncate_length, "no_arr": no_arr, "no_str": no_str}
    if is_message(value):
        names = value.get_fields_and_field_types()
        return ",".join(
            format_csv(getattr(value, name), slot, **options)
            for name, slot in zip(names, value.SLOT_TYPES, strict=True)
        )
    if isinstance(value, list | tuple | array.array | numpy.ndarray):
        if no_arr and field_type is not None:
            return abbreviated_array(value, field_type)
        items = [format_csv(item, **options) for item in list(value)[:truncate_length]]
        too_long = truncate_length is not None and len(value) > truncate_length
        return ",".join([*items, "..."] if too_long else items)
    if isinstance(value, str) and no_str:
        return f"<string length: <{len(value)}>>"
    if isinstance(value, str | bytes) and truncate_length is not None:
        cut = value[:truncate_length] + (b"..." if isinstance(value, bytes) else "...")
        value = cut if len(value) > truncate_length else value
    return str(value)


# --------------------------------------------------------------- YAML into a message
def message_class(type_name: str) -> type:
    """Import a message class from its name `pkg/msg/Type`."""
    try:
        package, kind, name = type_name.split("/")
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ValueError, ImportError, AttributeError) as error:
        raise CliError(f"The message type '{type_name}' is invalid or not built") from error


def set_message_fields(message: Any, values: dict, now: Callable[[], Any]) -> None:
    """Fill a message from a YAML mapping like rosidl_runtime_py.set_message_fields, with
    `header: auto` (stamp now, frame_id '') and `stamp: now` (a builtin Time) expanded."""
    import numpy
    from rosidl_parser import definition

    if not isinstance(values, dict):
        raise TypeError(f'Value "{values}" is invalid, it should be a dictionary')
    slot_types = dict(zip(message.get_fields_and_field_types(), message.SLOT_TYPES, strict=True))
    for name, given in values.items():
        current = getattr(message, name)  # AttributeError names the missing field
        kind = type(current)
        qualified = f"{kind.__module__}.{kind.__name__}"
        if qualified == "std_msgs.msg._header.Header" and given == "auto":
            current.stamp = now()
            continue
        if qualified == "builtin_interfaces.msg._time.Time" and given == "now":
            setattr(message, name, now())
            continue
        slot = slot_types[name]
        if isinstance(slot, definition.AbstractNestedType) and isinstance(
            slot.value_type, definition.NamespacedType
        ):
            if not isinstance(given, list):
                raise ValueError(f"field '{name}' must be a list")
            element = message_class("/".join(slot.value_type.namespaced_name()))
            items = []
            for item in given:
                submessage = element()
                set_message_fields(submessage, item, now)
                items.append(submessage)
            setattr(message, name, items)
        elif is_message(current):
            set_message_fields(current, given, now)
        elif isinstance(current, array.array):
            setattr(message, name, array.array(current.typecode, given))
        elif isinstance(current, numpy.ndarray):  # fixed-size array fields
            setattr(message, name, numpy.array(given, dtype=current.dtype))
        else:
            setattr(message, name, given if type(given) is kind else kind(given))


# -------------------------------------------------------------------------------- hz
class RateWindow:
    """ros2 topic hz's statistics (ros2topic.verb.hz.ROSTopicHz): arrival times in
    nanoseconds of the chosen clock, a report once that clock has advanced a second."""

    def __init__(self, window_size: int) -> None:
        self.periods_ns: deque[int] = deque(maxlen=window_size)
        self.first_ns = -1
        self.last_ns = 0
        self.last_printed_ns = 0

    def add(self, now_ns: int) -> str | None:
        """Record an arrival; a message to print when the clock went back to zero."""
        if now_ns == 0:  # ROS time not started yet (/clock silent) or reset
            if self.periods_ns:
                self.periods_ns.clear()
                return "time has reset, resetting counters"
            return None
        if self.first_ns < 0 or self.first_ns > now_ns:
            self.first_ns = self.last_ns = now_ns
            self.periods_ns.clear()
        else:
            self.periods_ns.append(now_ns - self.last_ns)
            self.last_ns = now_ns
        return None

    def report(self) -> str | None:
        """The `average rate` lines, or None while there is nothing new to say."""
        if not self.periods_ns:
            return None
        if self.last_printed_ns == 0:
            self.last_printed_ns = self.last_ns
            return None
        if self.last_ns < self.last_printed_ns + 1e9:
            return None
        periods = list(self.periods_ns)
        mean = sum(periods) / len(periods)
        rate = 1.0 / mean if mean > 0 else 0.0
        std_dev = math.sqrt(sum((x - mean) ** 2 for x in periods) / len(periods))
        self.last_printed_ns = self.last_ns
        return (
            f"average rate: {rate * 1e9:.3f}\n\tmin: {min(periods) * 1e-9:.3f}s "
            f"max: {max(periods) * 1e-9:.3f}s std dev: {std_dev * 1e-9:.5f}s "
            f"window: {len(periods)}"
        )


# -------------------------------------------------------------------------------- bw
def bytes_text(size_bytes: float, unit_bytes: float) -> str:
    """A size in ros2 topic bw's unit of the moment: B, KB or MB (powers of 1000)."""
    if unit_bytes == 1:
        return f"{size_bytes:.0f} B"
    return f"{size_bytes / unit_bytes:.2f} {'KB' if unit_bytes == 1e3 else 'MB'}"


class BandwidthWindow:
    """ros2 topic bw's statistics (ros2topic.verb.bw.ROSTopicBandwidth): the arrival times
    [s] and serialised sizes [B] of the last window_size messages."""

    def __init__(self, window_size: int) -> None:
        self.arrivals: deque[tuple[float, int]] = deque(maxlen=window_size)

    def add(self, now_s: float, size_bytes: int) -> None:
        self.arrivals.append((now_s, size_bytes))

    def report(self, now_s: float) -> str | None:
        """`N B/s from M messages` and the message sizes, or None before two messages
        (ros2cli's once-a-second line): the window's bytes over the time since its first."""
        if len(self.arrivals) < 2:
            return None
        first_s = self.arrivals[0][0]
        if now_s <= first_s:  # the clock went back (sim time reset): start again
            self.arrivals.clear()
            return None
        sizes = [size for _arrival, size in self.arrivals]
        rate = sum(sizes) / (now_s - first_s)
        unit = 1 if rate < 1e3 else 1e3 if rate < 1e6 else 1e6
        mean, smallest, largest = (
            bytes_text(x, unit) for x in (sum(sizes) / len(sizes), min(sizes), max(sizes))
        )
        return (f"{bytes_text(rate, unit)}/s from {len(sizes)} messages\n"
                f"\tMessage size mean: {mean} min: {smallest} max: {largest}")


# -------------------------------------------------------------------------- bag info
def format_size(size_bytes: int) -> str:
    """rosbag2's file size: B, KiB, MiB ... with one decimal above bytes."""
    size, index = float(size_bytes), 0
    units = ["B", "KiB", "MiB", "GiB", "TiB"]
    while size >= 1024 and index < 4:
        size /= 1024
        index += 1
    return f"{size:.{0 if index == 0 else 1}f} {units[index]}"


def format_seconds(nanoseconds: int) -> str:
    """Seconds with nine decimals, as rosbag2 prints durations and time points."""
    return f"{nanoseconds // 10**9}.{nanoseconds % 10**9:09d}"


def format_time_point(nanoseconds: int) -> str:
    """`Dec  2 2026 04:48:56.589617653 (1796186936.589617653)` in local time."""
    local = time.localtime(nanoseconds // 10**9)
    fraction = f"{nanoseconds % 10**9:09d}"
    clock = time.strftime("%b %e %Y %H:%M:%S", local)
    return f"{clock}.{fraction} ({format_seconds(nanoseconds)})"


def is_service_event_topic(name: str, type_name: str) -> bool:
    return name.endswith("/_service_event") and type_name.endswith("_Event")


def format_bag_info(metadata: dict, bag_size: int) -> str:
    """`ros2 bag info`'s text (Jazzy rosbag2_py format_bag_meta_data) for a metadata.yaml's
    rosbag2_bagfile_information mapping and the size of the bag's files."""
    indent = " " * 19
    topics = metadata.get("topics_with_message_count") or []
    services = [
        t for t in topics
        if is_service_event_topic(t["topic_metadata"]["name"], t["topic_metadata"]["type"])
    ]
    plain = [t for t in topics if t not in services]
    start_ns = int(metadata["starting_time"]["nanoseconds_since_epoch"])
    duration_ns = int(metadata["duration"]["nanoseconds"])
    files = metadata.get("relative_file_paths") or []
    lines = [
        "",
        "Files:             " + f"\n{indent}".join(files),
        f"Bag size:          {format_size(bag_size)}",
        f"Storage id:        {metadata.get('storage_identifier', '')}",
        f"ROS Distro:        {metadata.get('ros_distro') or 'unknown'}",
        f"Duration:          {format_seconds(duration_ns)}s",
        f"Start:             {format_time_point(start_ns)}",
        f"End:               {format_time_point(start_ns + duration_ns)}",
        "Messages:          "
        f"{int(metadata.get('message_count', 0)) - sum(t['message_count'] for t in services)}",
    ]

    def topic_line(t: dict) -> str:
        meta = t["topic_metadata"]
        return (
            f"Topic: {meta['name']} | Type: {meta['type']} | Count: {t['message_count']} | "
            f"Serialization Format: {meta['serialization_format']}"
        )

    def service_line(t: dict) -> str:
        meta = t["topic_metadata"]
        name = meta["name"][: -len("/_service_event")]
        kind = meta["type"][: -len("_Event")]
        return (
            f"Service: {name} | Type: {kind} | Event Count: {t['message_count']} | "
            f"Serialization Format: {meta['serialization_format']}"
        )

    lines.append("Topic information: " + f"\n{indent}".join(topic_line(t) for t in plain))
    lines.append(f"Service:           {len(services)}")
    lines.append(
        "Service information: " + f"\n{indent}  ".join(service_line(t) for t in services)
    )
    return "\n".join(lines)


def bag_info(path: str) -> str:
    """`ros2 bag info` of a rosbag2 directory (metadata.yaml and its storage files)."""
    directory = Path(path)
    metadata_path = directory / "metadata.yaml"
    if not metadata_path.is_file():
        raise CliError(f"Could not read metadata for {path}: no metadata.yaml found")
    try:
        metadata = yaml.safe_load(metadata_path.read_text())["rosbag2_bagfile_information"]
    except (yaml.YAMLError, TypeError, KeyError) as error:
        raise CliError(f"Could not read metadata for {path}: {error}") from error
    size = sum(
        os.path.getsize(directory / name)
        for name in metadata.get("relative_file_paths") or []
        if (directory / name).is_file()
    )
    return format_bag_info(metadata, size)
