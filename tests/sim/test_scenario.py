"""The scenario loader: the shipped files load; every kind of mistake gets one clear message."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import yaml
from helpers.flights import fly
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import ScenarioError, SensorDropout, default_scenario_path, load_scenario


def write(tmp_path, data) -> str:
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data) if not isinstance(data, str) else data)
    return str(path)


@pytest.fixture
def default_data():
    return yaml.safe_load(default_scenario_path().read_text())


@pytest.mark.parametrize("path", sorted(scenarios_dir().glob("*.yaml")), ids=lambda p: p.name)
def test_shipped_scenarios_load(path):
    scenario = load_scenario(path)
    assert scenario.duration_s > 0 and len(scenario.waypoints_ne_m) >= 2


def test_default_scenario_values(default_data):
    scenario = load_scenario(default_scenario_path())
    assert scenario.name == "default" and scenario.seed == default_data["seed"]
    assert scenario.faults_pct(0.0)["right_wing_lift_loss"] == 0.0
    assert scenario.faults_pct(70.0)["right_wing_lift_loss"] == pytest.approx(5.0)
    assert scenario.faults_pct(300.0)["left_wing_drag_increase"] == pytest.approx(25.0)


def edit(data, dotted_key, value):
    """Set (or with value None, delete) a nested key of the scenario data."""
    *parents, last = dotted_key.split(".")
    node = data
    for key in parents:
        node = node[int(key)] if isinstance(node, list) else node[key]
    if value is None:
        del node[last]
    else:
        node[last] = value
    return data


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("colour", "red", "unknown key 'colour'"),
        ("wind.gusts", 3, "unknown key 'wind.gusts'"),
        ("duration_s", None, "missing required key 'duration_s'"),
        ("initial.airspeed_mps", None, "missing required key 'initial.airspeed_mps'"),
        ("duration_s", "long", "'duration_s' must be a finite number"),
        ("duration_s", -5, "'duration_s' must be positive"),
        ("seed", 1.5, "'seed' must be a non-negative integer"),
        ("wind.turbulence", "strong", "'wind.turbulence' must be one of from_wind, none, light"),
        ("sensors", "all", "'sensors' must be a mapping"),
        ("sensors.pitot", True, "unknown key 'sensors.pitot' (known: air_data, noise)"),
        ("sensors.air_data", "yes", "'sensors.air_data' must be true or false, got 'yes'"),
        ("sensors.noise", 1, "'sensors.noise' must be true or false, got 1"),
        ("faults.0.name", "left_engine_fire", "'faults[0].name' must be one of"),
        ("faults.0.ramp_s", -1, "'faults[0].ramp_s' must be at least 0"),
        ("waypoints_ne_m", [[0, 0]], "needs at least two"),
        ("waypoints_ne_m", [[0, 0], [1, "x"]], "'waypoints_ne_m[1]' must be [north_m, east_m]"),
        (
            "sensor_dropouts",
            [{"channel": "pitot", "start_s": 1, "end_s": 2}],
            "'sensor_dropouts[0].channel' must be one of",
        ),
        (
            "sensor_dropouts",
            [{"channel": "roll", "start_s": 2, "end_s": 1}],
            "'sensor_dropouts[0].end_s' must be after start_s",
        ),
    ],
)
def test_bad_scenarios_name_the_file_and_the_key(tmp_path, default_data, key, value, message):
    path = write(tmp_path, edit(default_data, key, value))
    with pytest.raises(ScenarioError) as error:
        load_scenario(path)
    assert message in str(error.value)
    assert str(error.value).startswith(f"scenario {path}: ")
    assert "\n" not in str(error.value)


def test_an_air_data_dropout_needs_air_data_on_board(tmp_path, default_data):
    default_data["sensors"] = {"air_data": False}
    default_data["sensor_dropouts"] = [{"channel": "sideslip", "start_s": 1, "end_s": 2}]
    with pytest.raises(ScenarioError) as error:
        load_scenario(write(tmp_path, default_data))
    assert ("'sensor_dropouts[0].channel' is 'sideslip', an air-data channel, but "
            "sensors.air_data is false") in str(error.value)


def test_sensors_default_to_air_data_and_noise(tmp_path, default_data):
    del default_data["sensors"]
    scenario = load_scenario(write(tmp_path, default_data))
    assert scenario.sensors.air_data and scenario.sensors.noise
    default_data["sensors"] = {"noise": False}
    scenario = load_scenario(write(tmp_path, default_data))
    assert scenario.sensors.air_data and not scenario.sensors.noise


def test_air_data_dropouts_are_nan_in_the_air_data_only(default_scenario):
    scenario = dataclasses.replace(
        default_scenario, duration_s=3.0,
        sensor_dropouts=(SensorDropout("angle_of_attack", 1.0, 2.0),))
    samples = fly(scenario)
    missing = [s.time_s for s in samples if np.isnan(s.air_data).any()]
    assert missing == pytest.approx([1.0 + 0.05 * k for k in range(20)])
    assert all(np.isnan(s.air_data).sum() <= 1 and np.isfinite(s.state).all() for s in samples)


def test_unreadable_and_malformed_files(tmp_path):
    with pytest.raises(ScenarioError, match="cannot read the file"):
        load_scenario(tmp_path / "missing.yaml")
    with pytest.raises(ScenarioError, match="not valid YAML"):
        load_scenario(write(tmp_path, "name: [unclosed"))
    with pytest.raises(ScenarioError, match="'the file' must be a mapping"):
        load_scenario(write(tmp_path, "- just\n- a list\n"))


SHIPPED = sorted(default_scenario_path().parent.glob("*.yaml"))


@pytest.mark.timeout(30)
@pytest.mark.parametrize("path", SHIPPED, ids=[path.stem for path in SHIPPED])
def test_every_shipped_scenario_loads_under_its_file_name(path):
    scenario = load_scenario(path)
    assert scenario.name == path.stem
    assert scenario.duration_s == 300
