"""Edit nested YAML-like data by a dotted key: the strict-file tests (scenarios, airframes)
break one key at a time."""

from __future__ import annotations

from typing import Any


def edit(data: Any, dotted_key: str, value: Any) -> Any:
    """Set data's nested key (list items by index: "faults.0.name") to value, or delete it
    for value None; data itself, changed in place."""
    *parents, last = dotted_key.split(".")
    node = data
    for key in parents:
        node = node[int(key)] if isinstance(node, list) else node[key]
    if value is None:
        del node[last]
    else:
        node[last] = value
    return data
