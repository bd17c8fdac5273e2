"""Nested YAML-like data: edit it by a dotted key (the strict-file tests, scenarios and
airframes, break one key at a time) and compare two such (a shipped file against what its
command makes here)."""

from __future__ import annotations

from typing import Any

import pytest


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


# The simulation's floating-point results differ between CPUs (vector units, libm) at about
# 1e-8 relative, and an optimiser's maximum-likelihood fit moves further for it (measured:
# the detector calibration's Weibull fits by up to 4.3e-5): a file made on one machine is
# the same file to this tolerance on another.
MACHINE_RELATIVE_TOLERANCE = 1e-3


def assert_same_numbers(actual: Any, expected: Any, path: str = "") -> None:
    """Nested YAML-like data equal in structure and text, numbers within
    MACHINE_RELATIVE_TOLERANCE; AssertionError naming the first key that differs."""
    where = path or "top level"
    if isinstance(expected, dict):
        assert isinstance(actual, dict) and actual.keys() == expected.keys(), where
        for key in expected:
            assert_same_numbers(actual[key], expected[key], f"{path}.{key}" if path else key)
    elif isinstance(expected, list):
        assert isinstance(actual, list) and len(actual) == len(expected), where
        for index, (a, e) in enumerate(zip(actual, expected, strict=True)):
            assert_same_numbers(a, e, f"{path}.{index}")
    elif isinstance(expected, float) and not isinstance(expected, bool):
        assert actual == pytest.approx(expected, rel=MACHINE_RELATIVE_TOLERANCE, abs=0.0), where
    else:
        assert actual == expected, where
