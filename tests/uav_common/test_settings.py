"""Settings that own their defaults: a field declared once gives the settings' immutable
default and the node's ParameterSpec; a node's values (lists) become the settings, its own
parameters left out; a change names a field or is refused."""

from __future__ import annotations

import dataclasses

import pytest
from uav_common.settings import (
    ParameterSpec,
    parameter_specs,
    replaced,
    setting,
    settings_from,
)


@dataclasses.dataclass(frozen=True)
class Example:
    names: tuple[str, ...] = setting("names [-]", ["a", "b"])
    gain: float = setting("a gain [-]", 2.0, 0.0, 10.0, live=True)
    mode: str = setting("a mode", "fast", choices=("fast", "slow"))


@pytest.mark.timeout(10)
def test_a_field_gives_the_default_and_the_nodes_spec():
    assert Example() == Example(("a", "b"), 2.0, "fast")
    assert parameter_specs(Example) == {
        "names": ParameterSpec("names [-]", ["a", "b"]),
        "gain": ParameterSpec("a gain [-]", 2.0, 0.0, 10.0, live=True),
        "mode": ParameterSpec("a mode", "fast", choices=("fast", "slow")),
    }
    with pytest.raises(dataclasses.FrozenInstanceError):
        Example().gain = 3.0  # type: ignore[misc]


@pytest.mark.timeout(10)
def test_a_nodes_values_become_the_settings_and_a_change_names_a_field():
    values = {"names": ["c"], "gain": 4.0, "qos": "reliable"}  # qos: the node's own
    settings = settings_from(Example, values)
    assert settings == Example(("c",), 4.0, "fast")
    assert replaced(settings, {"names": ["d", "e"]}) == Example(("d", "e"), 4.0, "fast")
    with pytest.raises(TypeError, match="qos"):
        replaced(settings, {"qos": "sensor_data"})
