"""The scenario loader: the shipped files load; every kind of mistake gets one clear message."""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers.flights import fly
from helpers.nested import edit
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import (
    MAX_SCENARIO_BYTES,
    MAX_WAYPOINTS,
    ScenarioError,
    SensorDropout,
    default_scenario_path,
    load_scenario,
)


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
        ("sensors.pitot", True, "unknown key 'sensors.pitot' (known: air_data, noise, vanes)"),
        ("sensors.air_data", "yes", "'sensors.air_data' must be true or false, got 'yes'"),
        ("sensors.noise", 1, "'sensors.noise' must be true or false, got 1"),
        ("faults.0.name", "left_engine_fire", "'faults[0].name' must be one of"),
        ("faults.0.ramp_s", -1, "'faults[0].ramp_s' must be at least 0"),
        ("waypoints_ne_m", [[0, 0]], "needs at least two"),
        ("waypoints_ne_m", [[0, 0], [1, "x"]], "'waypoints_ne_m[1]' must be [north_m, east_m]"),
        ("waypoints_ne_m", [[0, 0], [500, 0], [500, 0], [0, 500]],
         "'waypoints_ne_m[2]' is the same point as 'waypoints_ne_m[1]': a leg needs two"),
        ("waypoints_ne_m", [[0, 0], [500, 0], [0, 0]],
         "'waypoints_ne_m[0]' is the same point as 'waypoints_ne_m[2]'"),
        ("aircraft", {"wingspan_scale": 1.1}, "unknown key 'aircraft.wingspan_scale' (known: "),
        ("aircraft", {"mass_scale": 2.5}, "'aircraft.mass_scale' must be at most 2"),
        ("aircraft", {"coefficients": {"CLbeta": 1.1}},
         "unknown key 'aircraft.coefficients.CLbeta'"),
        ("aircraft", {"coefficients": {"CDmin": 0.4}},
         "'aircraft.coefficients.CDmin' must be at least 0.5"),
        ("aircraft", {"inertia_scale": [1.0, 1.1]}, "'aircraft.inertia_scale' must be [x, y, z]"),
        ("aircraft", {"sensor_bias": {"angle_of_attack_deg": 6}},
         "'aircraft.sensor_bias.angle_of_attack_deg' must be at most 5"),
        ("guidance", {"method": "pure_pursuit"}, "'guidance.method' must be one of"),
        ("guidance", {"method": "vector_field", "horizon_steps": 12},
         "'guidance.method' is vector_field: the MPC settings (horizon_steps) belong to"),
        ("guidance", {"method": "mpc", "horizon_steps": 1},
         "'guidance.horizon_steps' must be in 2..100"),
        ("guidance", {"method": "mpc", "sample_s": 0}, "'guidance.sample_s' must be at least"),
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
        ("setpoints", [{"start_s": 60}], "'setpoints[0].start_s': a setpoint change needs"),
        ("setpoints", [{"start_s": 60, "airspeed_mps": 0}],
         "'setpoints[0].airspeed_mps' must be"),
        ("setpoints", [{"start_s": -1, "altitude_m": 300}],
         "'setpoints[0].start_s' must be at least 0"),
        ("setpoints", [{"start_s": 60, "heading_deg": 90}],
         "unknown key 'setpoints[0].heading_deg'"),
        ("vehicle", "cessna_172", "'vehicle': unknown vehicle 'cessna_172' (known: aerosonde, "
                                  "carbon_z)"),
        ("aircraft", {"coefficients": {"CLalpha": 1.1}, "vehicle_scale": 1.0},
         "unknown key 'aircraft.vehicle_scale'"),
        ("faults", [{"name": "elevator_stuck", "start_s": 60, "position": 1.5}],
         "'faults[0].position' must be at most 1"),
        ("faults", [{"name": "engine_cut", "start_s": 60, "position": 0.2}],
         "unknown key 'faults[0].position' (known: name, start_s)"),
        ("faults", [{"name": "rudder_stuck", "start_s": 60, "ramp_s": 10}],
         "unknown key 'faults[0].ramp_s' (known: name, position, start_s)"),
        ("faults", [{"name": "rudder_stuck", "start_s": 60},
                    {"name": "rudder_stuck", "start_s": 90, "position": -0.5}],
         "'faults[0].name': rudder_stuck is seeded more than once"),
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


def test_vanes_go_with_air_data_unless_a_pitot_flies_alone(tmp_path, default_data):
    default_data["sensors"] = {"vanes": False}
    sensors = load_scenario(write(tmp_path, default_data)).sensors
    assert sensors.air_data and not sensors.vanes
    default_data["sensors"] = {"air_data": False}
    assert not load_scenario(write(tmp_path, default_data)).sensors.vanes
    default_data["sensors"] = {"air_data": False, "vanes": True}
    with pytest.raises(ScenarioError) as error:
        load_scenario(write(tmp_path, default_data))
    assert ("'sensors.vanes' is true but 'sensors.air_data' is false: vanes are air data"
            in str(error.value))


def test_guidance_defaults_to_the_vector_field_and_reads_mpc_settings(tmp_path, default_data):
    default_data.pop("guidance", None)
    assert load_scenario(write(tmp_path, default_data)).guidance.method == "vector_field"
    default_data["guidance"] = {"method": "mpc", "horizon_steps": 15, "sample_s": 1.0}
    settings = load_scenario(write(tmp_path, default_data)).guidance.mpc
    assert (settings.horizon_steps, settings.sample_s) == (15, 1.0)


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


@pytest.mark.timeout(30)
def test_a_file_that_is_not_utf8_is_one_line_naming_it(tmp_path, default_data):
    path = tmp_path / "latin1.yaml"
    path.write_bytes(yaml.safe_dump(default_data).encode() + "# réglé\n".encode("latin-1"))
    with pytest.raises(ScenarioError) as error:
        load_scenario(path)
    offset = path.read_bytes().index(0xE9)
    assert str(error.value) == f"scenario {path}: not UTF-8 text (byte 0xe9 at offset {offset})"


@pytest.mark.timeout(30)
def test_a_file_above_the_size_limit_is_refused_before_parsing(tmp_path, default_data):
    """The issue's 37 MB file took 7.7 GB and 5 minutes: refused unparsed, read no further
    than the limit (the invalid YAML and /dev/zero's endless bytes are never parsed)."""
    big = tmp_path / "big.yaml"
    points = ", ".join(f"[{k}, {k}]" for k in range(300_000))
    big.write_text(yaml.safe_dump(default_data) + "waypoints_extra: [" + points + "\n")
    assert big.stat().st_size > 10 * MAX_SCENARIO_BYTES
    started = time.monotonic()
    for path in (big, Path("/dev/zero")):
        with pytest.raises(ScenarioError) as error:
            load_scenario(path)
        assert str(error.value) == (f"scenario {path}: larger than 64 KiB, the most a scenario "
                                    "file may be (the shipped ones are under 2 kB)")
    assert time.monotonic() - started < 5.0  # parsing 4 MB would take about 40 s


@pytest.mark.timeout(30)
def test_a_file_just_under_the_size_limit_loads(tmp_path, default_data):
    text = yaml.safe_dump(default_data)
    padding = "# a comment line of a long scenario file\n"
    text += padding * ((MAX_SCENARIO_BYTES - len(text)) // len(padding))
    path = write(tmp_path, text)
    assert MAX_SCENARIO_BYTES - len(padding) < Path(path).stat().st_size <= MAX_SCENARIO_BYTES
    assert load_scenario(path).name == "default"


@pytest.mark.timeout(30)
def test_the_waypoint_count_is_capped(tmp_path, default_data):
    square = [[0, 0], [1500, 0], [1500, 1500], [0, 1500]]
    default_data["waypoints_ne_m"] = square * (MAX_WAYPOINTS // 4)
    assert len(load_scenario(write(tmp_path, default_data)).waypoints_ne_m) == MAX_WAYPOINTS
    default_data["waypoints_ne_m"] = square * (MAX_WAYPOINTS // 4) + [[7, 7]]
    with pytest.raises(ScenarioError) as error:
        load_scenario(write(tmp_path, default_data))
    assert str(error.value).endswith(
        f": 'waypoints_ne_m' has {MAX_WAYPOINTS + 1} points, more than the {MAX_WAYPOINTS} a "
        "scenario may have")


@pytest.mark.timeout(30)
@pytest.mark.parametrize("name", ["../../etc", "/", "a/b", ".", ".."])
def test_the_name_must_be_a_folder_name(tmp_path, default_data, name):
    """demo.sh writes into runs/<name>/: no name may lead elsewhere."""
    default_data["name"] = name
    path = write(tmp_path, default_data)
    with pytest.raises(ScenarioError) as error:
        load_scenario(path)
    assert str(error.value).startswith(f"scenario {path}: 'name' must be usable as a folder name")


@pytest.mark.timeout(30)
def test_deeply_nested_yaml_is_one_line(tmp_path):
    path = write(tmp_path, "name: " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(ScenarioError) as error:
        load_scenario(path)
    assert str(error.value) == f"scenario {path}: not valid YAML (nested too deeply)"


def test_setpoint_changes_hold_from_their_start_in_time_order(tmp_path, default_data):
    default_data["setpoints"] = [{"start_s": 100, "altitude_m": 280},
                                 {"start_s": 60, "airspeed_mps": 28},
                                 {"start_s": 140, "airspeed_mps": 22, "altitude_m": 250}]
    scenario = load_scenario(write(tmp_path, default_data))
    first = (scenario.initial.airspeed_mps, scenario.initial.altitude_m)
    assert scenario.commanded(59.9) == first
    assert scenario.commanded(60.0) == (28.0, first[1])
    assert scenario.commanded(120.0) == (28.0, 280.0)
    assert scenario.commanded(1000.0) == (22.0, 250.0)
