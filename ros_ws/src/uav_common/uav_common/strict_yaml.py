"""Strict reading of the project's hand-written YAML files (scenarios, airframes): refused
before parsing when too large or not UTF-8, then every mapping checked key by key, so that
an unknown or missing key, a wrong type or an impossible value stops with one line naming
the file and the key's path. No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml


@dataclass(frozen=True)
class FileKind:
    """A kind of file: its word in every message ("scenario"), the ValueError subclass it
    raises, the most bytes it may have (refused before parsing) and what the shipped ones
    weigh (said when a file is refused for its size)."""

    label: str
    error: type[ValueError]
    max_bytes: int
    shipped_size: str


def kind_mismatch(data: Any, keys: Sequence[str], expected: str) -> str | None:
    """What is wrong, in words, when a parsed file is not of the kind expected (`expected`:
    what such a file is and what writes it) because it lacks one of the top-level `keys`
    every such file has, as a file of another kind does (a scenario given for a
    calibration): such a file's keys and what this one holds instead. None when it has
    them all (what else may be wrong with it is the reader's to say)."""
    if isinstance(data, dict) and all(key in data for key in keys):
        return None
    if isinstance(data, dict) and data:
        found = "the keys " + ", ".join(map(str, data))
    elif isinstance(data, dict) or data is None:
        found = "nothing"
    else:
        found = f"a {type(data).__name__}, not a mapping"
    return f"not {expected}, whose keys are {', '.join(keys)}; this file holds {found}"


def is_number(value: Any) -> bool:
    """A finite int or float (YAML's true/false are not numbers)."""
    return not isinstance(value, bool) and isinstance(value, int | float) and math.isfinite(value)


class Reader:
    """Checks one mapping of the file; every message names the file and the key's path."""

    def __init__(self, kind: FileKind, path: Path, data: Any, where: str) -> None:
        self.kind = kind
        self.path = path
        self.where = where
        if not isinstance(data, dict):
            self.fail(f"'{where or 'the file'}' must be a mapping, got {type(data).__name__}")
        self.data = data

    def fail(self, message: str) -> None:
        raise self.kind.error(f"{self.kind.label} {self.path}: {message}")

    def key(self, name: str) -> str:
        return f"{self.where}.{name}" if self.where else name

    def check_keys(self, required: set[str], optional: set[str] = frozenset()) -> None:
        for name in self.data:
            if name not in required | optional:
                known = ", ".join(sorted(required | optional))
                self.fail(f"unknown key '{self.key(str(name))}' (known: {known})")
        for name in sorted(required):
            if name not in self.data:
                self.fail(f"missing required key '{self.key(name)}'")

    def number(self, name: str, minimum: float | None = None, positive: bool = False,
               maximum: float | None = None) -> float:
        value = self.data[name]
        if not is_number(value):
            self.fail(f"'{self.key(name)}' must be a finite number, got {value!r}")
        if positive and value <= 0:
            self.fail(f"'{self.key(name)}' must be positive, got {value!r}")
        if minimum is not None and value < minimum:
            self.fail(f"'{self.key(name)}' must be at least {minimum:g}, got {value!r}")
        if maximum is not None and value > maximum:
            self.fail(f"'{self.key(name)}' must be at most {maximum:g}, got {value!r}")
        return float(value)

    def integer(self, name: str, minimum: int, maximum: int) -> int:
        """An int in minimum..maximum (a float such as 3.0 is refused: a count or index)."""
        value = self.data[name]
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(f"'{self.key(name)}' must be an integer, got {value!r}")
        if not minimum <= value <= maximum:
            self.fail(f"'{self.key(name)}' must be in {minimum}..{maximum}, got {value!r}")
        return value

    def text(self, name: str) -> str:
        """A non-empty string."""
        value = self.data[name]
        if not isinstance(value, str) or not value:
            self.fail(f"'{self.key(name)}' must be a non-empty string, got {value!r}")
        return value

    def flag(self, name: str, default: bool) -> bool:
        value = self.data.get(name, default)
        if not isinstance(value, bool):
            self.fail(f"'{self.key(name)}' must be true or false, got {value!r}")
        return value

    def choice(self, name: str, choices: tuple[Any, ...]) -> Any:
        value = self.data[name]
        # `in` alone would take YAML's true for 1 and 1.0 for 1
        if not any(type(value) is type(choice) and value == choice for choice in choices):
            listed = ", ".join(map(str, choices))
            self.fail(f"'{self.key(name)}' must be one of {listed}; got {value!r}")
        return value

    def items(self, name: str) -> list[Any]:
        value = self.data.get(name, [])
        if value is None:
            return []
        if not isinstance(value, list):
            self.fail(f"'{self.key(name)}' must be a list, got {type(value).__name__}")
        return value

    def child(self, name: str) -> Reader:
        return Reader(self.kind, self.path, self.data[name], self.key(name))

    def element(self, name: str, index: int) -> Reader:
        """The index-th mapping of the list under name (items(name))."""
        return Reader(self.kind, self.path, self.items(name)[index], f"{self.key(name)}[{index}]")


def _read_text(kind: FileKind, path: Path) -> str:
    """The file's text; kind.error when it cannot be read, is larger than kind.max_bytes
    (checked before it is parsed, and read no further than that) or is not UTF-8."""
    try:
        with path.open("rb") as file:
            content = file.read(kind.max_bytes + 1)
    except OSError as error:
        reason = error.strerror or type(error).__name__
        raise kind.error(f"{kind.label} {path}: cannot read the file ({reason})") from None
    if len(content) > kind.max_bytes:
        raise kind.error(
            f"{kind.label} {path}: larger than {kind.max_bytes // 1024} KiB, the most a "
            f"{kind.label} file may be ({kind.shipped_size})")
    try:
        return content.decode("utf-8")
    except UnicodeDecodeError as error:
        raise kind.error(
            f"{kind.label} {path}: not UTF-8 text (byte 0x{content[error.start]:02x} at offset "
            f"{error.start})") from None


def load_yaml(kind: FileKind, path: Path) -> Reader:
    """The file parsed, as a Reader of its top-level mapping; kind.error with one line when
    it cannot be read, is too large, not UTF-8, not YAML or not a mapping."""
    try:
        data = yaml.safe_load(_read_text(kind, path))
    except yaml.YAMLError as error:
        raise kind.error(f"{kind.label} {path}: not valid YAML ({' '.join(str(error).split())})"
                         ) from None
    except RecursionError:
        raise kind.error(f"{kind.label} {path}: not valid YAML (nested too deeply)") from None
    return Reader(kind, path, data, "")
