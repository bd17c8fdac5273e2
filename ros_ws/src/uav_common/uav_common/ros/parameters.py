"""Node parameters declared once each (a ParameterSpec, uav_common.settings), with a
descriptor (type, range or choices, live or read-only) and the spec's default; overrides
checked before anything is declared; live changes checked and handed to the node."""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from typing import Any

from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    SetParametersResult,
)
from rclpy.node import Node
from rclpy.parameter import Parameter

from uav_common.ros.parameter_files import wildcard_only_names
from uav_common.ros.qos import STREAM_QOS_PROFILES
from uav_common.settings import ParameterSpec

# Every stream node's `wait_for_subscribers` parameter (when_subscribed).
WAIT_FOR_SUBSCRIBERS_PARAMETER = ParameterSpec(
    "subscribe to the inputs only once the node's output has this many subscriptions, so "
    "that nothing it publishes is lost to discovery; 0: at once", 0, 0, 100)

# Every stream node's `qos` parameter (STREAM_QOS_PROFILES).
QOS_PARAMETER = ParameterSpec(
    "QoS of the node's sensor-rate streams: reliable (keep-all, nothing lost, a slow "
    "subscriber holds the publisher back) or sensor_data (best effort, newest 5: messages may "
    "be lost); a reliable subscription does not hear a sensor_data publisher", "reliable",
    choices=tuple(STREAM_QOS_PROFILES))


class ParameterError(ValueError):
    """A parameter override the node refuses (bad type, out of range, unknown)."""


_TYPE_NAMES = {
    Parameter.Type.BOOL: "a boolean", Parameter.Type.INTEGER: "an integer",
    Parameter.Type.DOUBLE: "a real number", Parameter.Type.STRING: "a string",
    Parameter.Type.BYTE_ARRAY: "a byte array", Parameter.Type.BOOL_ARRAY: "a boolean list",
    Parameter.Type.INTEGER_ARRAY: "an integer list", Parameter.Type.DOUBLE_ARRAY: "a real list",
    Parameter.Type.STRING_ARRAY: "a string list", Parameter.Type.NOT_SET: "no value",
}
_NUMBERS = (Parameter.Type.INTEGER, Parameter.Type.DOUBLE)
_NUMBER_ARRAYS = (Parameter.Type.INTEGER_ARRAY, Parameter.Type.DOUBLE_ARRAY)
# An integer given where a real is declared (`-p solver_eps_abs:=1`, `tau_a_s: 4` in a
# params file) is the real it names: taken as that real. Not the other way round: 50.0
# for a count is refused, as a real there is more likely a slip than a whole number.
_WIDENED = {Parameter.Type.INTEGER: Parameter.Type.DOUBLE,
            Parameter.Type.INTEGER_ARRAY: Parameter.Type.DOUBLE_ARRAY}


def _expected(kind: Parameter.Type, spec: ParameterSpec) -> str:
    text = _TYPE_NAMES[kind]
    if spec.range_text():
        text += (" in " if kind in _NUMBERS else " of values in ") + spec.range_text()
    return text


def checked_value(name: str, value: Any, kind: Parameter.Type, spec: ParameterSpec) -> Any:
    """value as the declared type `kind` (an integer widened to a real), in the spec's range;
    ParameterError, one line naming the parameter, otherwise."""
    given = Parameter.Type.from_parameter_value(value)
    if isinstance(value, list | tuple) and not value and kind.name.endswith("_ARRAY"):
        given = kind  # `[]` has no element to tell its type by
    if given != kind and _WIDENED.get(given) == kind:
        value = float(value) if kind == Parameter.Type.DOUBLE else [float(v) for v in value]
        given = kind
    if given != kind:
        raise ParameterError(f"parameter {name}: {value!r} is {_TYPE_NAMES[given]}; it must be "
                             f"{_expected(kind, spec)}")
    if spec.range_text() and kind in _NUMBERS + _NUMBER_ARRAYS:
        values = [value] if kind in _NUMBERS else list(value)
        bad = [v for v in values if not spec.low <= v <= spec.high]  # NaN is never in range
        if bad:
            raise ParameterError(f"parameter {name}: {bad[0]!r} is out of range; it must be "
                                 f"{_expected(kind, spec)}")
    if spec.choices and value not in spec.choices:
        raise ParameterError(f"parameter {name}: {value!r} is not a choice; it must be one of "
                             f"{spec.choices_text()}")
    return value


def _descriptor(kind: Parameter.Type, spec: ParameterSpec) -> ParameterDescriptor:
    # Read-only unless live: a value read once, at start, cannot follow a change at run
    # time, so `ros2 param set` is refused with that reason, never ignored.
    descriptor = ParameterDescriptor(description=spec.description, type=kind.value,
                                     read_only=not spec.live)
    if spec.range_text():
        if kind == Parameter.Type.DOUBLE:
            descriptor.floating_point_range = [
                FloatingPointRange(from_value=float(spec.low), to_value=float(spec.high))]
        elif kind == Parameter.Type.INTEGER:
            descriptor.integer_range = [
                IntegerRange(from_value=int(spec.low), to_value=int(spec.high), step=1)]
        elif kind in _NUMBER_ARRAYS:
            descriptor.additional_constraints = f"each value in {spec.range_text()}"
    if spec.choices:
        descriptor.additional_constraints = f"one of {spec.choices_text()}"
    return descriptor


# What a node does with changes of its live parameters (new values by name): apply them
# all, or none and raise ParameterError with the reason `ros2 param set` prints.
ApplyChanges = Callable[[dict[str, Any]], None]


def declare_parameters(
    node: Node, specs: Mapping[str, ParameterSpec], apply_changes: ApplyChanges | None = None,
) -> dict[str, Any]:
    """Declare each parameter with its default, type and range (its ParameterSpec) in its
    descriptor; the values by name.

    Values given on the command line or in a --params-file override the defaults, after a
    check: of the type (an integer is taken for a real), of the range, and that the node has
    such a parameter. A bad one raises ParameterError (one line) before anything is declared;
    a name the node lacks that only a file's `/**` section gave it is ignored, with one
    warning naming them all (parameter_files.py).
    Live parameters (ParameterSpec.live) changed at run time go, checked the same way, to
    apply_changes; once it has applied them the returned dict holds the new values.
    """
    defaults = {name: spec.default for name, spec in specs.items()}
    # rclpy keeps the overrides meant for this node (-p, --params-file) here; there is no
    # public accessor, and declaring would take a wrong one with rclpy's own traceback.
    overrides = {name: parameter.value for name, parameter in node._parameter_overrides.items()}
    unknown = sorted(name for name in overrides
                     if name not in specs and not node.has_parameter(name))
    shared = sorted(set(unknown) & wildcard_only_names(_process_arguments(), node.get_name()))
    if shared:  # a file written for every node: its keys for others are not this one's
        node.get_logger().warning(
            f"ignoring {', '.join(shared)} of the parameter file's /** section: this node "
            f"has no such parameter{'s' if len(shared) > 1 else ''}")
        unknown = [name for name in unknown if name not in shared]
    if unknown:
        raise ParameterError(
            f"unknown parameter{'s' if len(unknown) > 1 else ''} {', '.join(unknown)} (this "
            f"node has: {', '.join(sorted(specs))})")
    values = {}
    for name, spec in specs.items():
        kind = Parameter.Type.from_parameter_value(defaults[name])
        checked_value(name, defaults[name], kind, spec)  # the shipped default fits, too
        values[name] = checked_value(name, overrides.get(name, defaults[name]), kind, spec)
    for name, spec in specs.items():
        kind = Parameter.Type.from_parameter_value(defaults[name])
        node.declare_parameter(name, values[name], _descriptor(kind, spec), ignore_override=True)
    values = {name: node.get_parameter(name).value for name in specs}
    kinds = {name: Parameter.Type.from_parameter_value(defaults[name]) for name in specs}
    node.add_pre_set_parameters_callback(
        lambda parameters: [_widened(parameter, kinds) for parameter in parameters])
    live = {name: spec for name, spec in specs.items() if spec.live}
    if live:
        if apply_changes is None:
            raise TypeError(f"live parameters {sorted(live)} need apply_changes")
        node.add_on_set_parameters_callback(
            lambda parameters: _set_live(parameters, live, values, apply_changes))
    return values


def _widened(parameter: Parameter, kinds: Mapping[str, Parameter.Type]) -> Parameter:
    """The pre-set callback's step: an integer (or integer array) set on a real (or real
    array) parameter becomes the real it names, as at start (`ros2 param set ... 8`)."""
    kind = kinds.get(parameter.name)
    if kind is None or _WIDENED.get(parameter.type_) != kind:
        return parameter
    value = parameter.value
    return Parameter(parameter.name, kind,
                     float(value) if kind == Parameter.Type.DOUBLE else [float(v) for v in value])


def _set_live(parameters: list[Parameter], live: Mapping[str, ParameterSpec],
              values: dict[str, Any], apply_changes: ApplyChanges) -> SetParametersResult:
    """The on-set callback: rclpy has refused read-only ones and values outside a
    descriptor's range already; the same checks as at start, then the node applies them."""
    try:
        changes = {parameter.name: checked_value(
            parameter.name, parameter.value, Parameter.Type.from_parameter_value(
                values[parameter.name]), live[parameter.name])
            for parameter in parameters if parameter.name in live}
        if changes:
            apply_changes(changes)
    except ParameterError as error:
        return SetParametersResult(successful=False, reason=str(error))
    values.update(changes)
    return SetParametersResult(successful=True)


class NodeArguments:
    """The arguments rclpy was initialised with by the node's main (None: the process's own):
    where its parameter overrides came from."""

    given: list[str] | None = None


def _process_arguments() -> list[str]:
    """The arguments the node's ROS arguments come from."""
    return NodeArguments.given if NodeArguments.given is not None else sys.argv
