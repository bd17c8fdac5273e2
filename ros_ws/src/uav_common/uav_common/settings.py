"""Settings that own their defaults: a core's frozen dataclass whose fields are its node's
parameters, each declared once, with its ParameterSpec (description with its unit, default,
range or choices, live or not). The node builds its ParameterSpecs from the fields
(parameter_specs) and turns its values into the settings in one call (settings_from);
offline code constructs the dataclass (`ResidualSettings(vehicle="carbon_z")`, or
`dataclasses.replace`). No rclpy here: the cores import it, and uav_common.ros.parameters
declares a ParameterSpec as a ROS parameter."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, TypeVar

_SPEC = "parameter"  # a settings field's metadata key of its ParameterSpec
Settings = TypeVar("Settings")


@dataclass(frozen=True)
class ParameterSpec:
    """What a node says about one of its parameters, the one place it is declared: its
    description (its unit in brackets at the end); its default, whose type is the
    parameter's (4.0 a real, 4 an integer, [] a list of strings); for numbers, the closed
    range [low, high] its values (each element of an array) must lie in; for a string, the
    choices it must be one of, and what the empty string means when it is one of them
    (empty_choice: "the scenario's"); and whether the node applies a change at run time
    (live) or reads it once, at start (read-only). The package's config/<node>.yaml and the
    docs' parameter tables are generated from these (tools/parameter_pages.py)."""

    description: str
    default: Any
    low: float | None = None
    high: float | None = None
    live: bool = False
    choices: tuple[str, ...] = ()
    empty_choice: str = ""

    def range_text(self) -> str:
        return "" if self.low is None or self.high is None else f"[{self.low:g}, {self.high:g}]"

    def choice_text(self, choice: str) -> str:
        """A choice as a message lists it: the empty string as '' and what it means."""
        if choice:
            return choice
        return "''" + (f" ({self.empty_choice})" if self.empty_choice else "")

    def choices_text(self) -> str:
        """The choices as a message lists them: `'' (the scenario's), aerosonde, carbon_z`."""
        return ", ".join(map(self.choice_text, self.choices))


def declared_setting(spec: ParameterSpec) -> Any:
    """A settings field declared by spec: its default the spec's (a list as a tuple: settings
    are immutable), the spec in the field's metadata."""
    default = tuple(spec.default) if isinstance(spec.default, list) else spec.default
    return dataclasses.field(default=default, metadata={_SPEC: spec})


def setting(description: str, default: Any, low: float | None = None,
            high: float | None = None, live: bool = False, choices: tuple[str, ...] = ()) -> Any:
    """A settings field: its ParameterSpec's arguments (a list default for a list)."""
    return declared_setting(ParameterSpec(description, default, low, high, live, choices))


def parameter_specs(settings_type: type) -> dict[str, ParameterSpec]:
    """The ParameterSpec of each field of a settings dataclass, in the fields' order."""
    return {field.name: field.metadata[_SPEC] for field in dataclasses.fields(settings_type)}


def settings_from(settings_type: type[Settings], values: Mapping[str, Any]) -> Settings:
    """The settings of values by name (a node's parameters; a list taken as a tuple); names
    that are not fields (the node's own parameters) are left out, fields not given keep
    their defaults."""
    names = {field.name for field in dataclasses.fields(settings_type)}
    return settings_type(**{name: _frozen(value) for name, value in values.items()
                            if name in names})


def replaced(settings: Settings, changes: Mapping[str, Any]) -> Settings:
    """The settings with changed values by name (a list taken as a tuple); TypeError for a
    name that is not a field."""
    return dataclasses.replace(settings, **{name: _frozen(value)
                                            for name, value in changes.items()})


def _frozen(value: Any) -> Any:
    return tuple(value) if isinstance(value, list) else value
