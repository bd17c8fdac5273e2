"""The airframe file: the example loads; every kind of mistake is one line naming the file and
the key; PWM and normalised outputs become deflections on known values; mixed outputs are
checked against the log."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers.nested import edit
from uav_aircraft.airframe import AirframeError, load_airframe
from uav_aircraft.vehicles import load_vehicle
from uav_fault_estimator.flight_logs.streams import OUTPUTS, FlightLog, TimedSeries
from uav_fault_estimator.flight_logs.surfaces import mixed_output_mismatches, surface_deflections

EXAMPLE = load_vehicle("aerosonde").airframe_files["aerosonde_sim"]
# the airframe of the test logs written from simulated flights (tests/helpers/simulated_logs)
FIXTURE = Path(__file__).parent / "fixture_airframe.yaml"

PWM_AIRFRAME = {
    "name": "test_plane",
    "output_unit": "pwm_us",
    "surfaces": {
        "aileron": {"output": 1, "trim_us": 1500, "throw_us": 400, "max_deflection_rad": 0.4,
                    "sign": 1},
        "elevator": {"output": 2, "trim_us": 1520, "throw_us": 500, "max_deflection_rad": 0.5,
                     "sign": -1},
        "rudder": {"output": 4, "trim_us": 1480, "throw_us": 300, "max_deflection_rad": 0.3,
                   "sign": 1},
        "throttle": {"output": 3, "idle_us": 1100, "full_us": 1900},
    },
    "mixed": [{"output": 5, "of_output": 1, "factor": -1.0}],
}


def write(tmp_path, data) -> str:
    path = tmp_path / "airframe.yaml"
    path.write_text(yaml.safe_dump(data) if not isinstance(data, str) else data)
    return str(path)


def edited(dotted_key: str, value):
    """PWM_AIRFRAME with one key set (value None: deleted); list items by index."""
    return edit(copy.deepcopy(PWM_AIRFRAME), dotted_key, value)


def outputs_log(times_s, columns: dict[str, list[float]], unit: str = "pwm_us") -> FlightLog:
    series = TimedSeries(np.asarray(times_s, dtype=float),
                         np.column_stack([np.asarray(v, dtype=float) for v in columns.values()]),
                         tuple(columns))
    return FlightLog("synthetic", "synthetic.ulg", "ulog", {OUTPUTS: series}, output_unit=unit)


@pytest.mark.timeout(10)
def test_the_example_airframe_loads():
    airframe = load_airframe(EXAMPLE)
    assert airframe.name == "aerosonde_sim" and airframe.output_unit == "pwm_us"
    assert set(airframe.controls) == {"aileron", "elevator", "rudder", "throttle"}
    assert airframe.controls["aileron"].scale == pytest.approx(0.5236)
    assert airframe.axes is None and airframe.airspeed_source is None


@pytest.mark.timeout(10)
def test_the_test_logs_airframe_loads():
    airframe = load_airframe(FIXTURE)
    assert airframe.controls["aileron"].span == -400.0  # a reversed servo
    assert [(m.output, m.of_output, m.factor) for m in airframe.mixed] == [(5, 1, -1.0)]


@pytest.mark.timeout(10)
def test_a_full_airframe_loads(tmp_path):
    data = dict(PWM_AIRFRAME, axes="FLU", airspeed_source="indicated")
    airframe = load_airframe(write(tmp_path, data))
    assert (airframe.axes, airframe.airspeed_source) == ("FLU", "indicated")
    assert [(m.output, m.of_output, m.factor) for m in airframe.mixed] == [(5, 1, -1.0)]
    assert airframe.controls["elevator"].span == -500.0  # sign -1


@pytest.mark.timeout(10)
@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("colour", "red", "unknown key 'colour'"),
        ("surfaces.flap", {"output": 6}, "unknown key 'surfaces.flap'"),
        ("surfaces.aileron.trim", 1500, "unknown key 'surfaces.aileron.trim'"),
        ("name", None, "missing required key 'name'"),
        ("surfaces.elevator", None, "missing required key 'surfaces.elevator'"),
        ("surfaces.aileron.throw_us", None, "missing required key 'surfaces.aileron.throw_us'"),
        ("name", "", "'name' must be a non-empty string"),
        ("surfaces", [1, 2], "'surfaces' must be a mapping"),
        ("surfaces.aileron.output", "one", "'surfaces.aileron.output' must be an integer"),
        ("surfaces.aileron.output", 1.0, "'surfaces.aileron.output' must be an integer"),
        ("surfaces.aileron.output", 0, "'surfaces.aileron.output' must be in 1..16, got 0"),
        ("surfaces.rudder.output", 17, "'surfaces.rudder.output' must be in 1..16, got 17"),
        ("surfaces.rudder.output", 2, "'surfaces.rudder.output' is output 2, already elevator's"),
        ("surfaces.aileron.sign", 2, "'surfaces.aileron.sign' must be one of 1, -1; got 2"),
        ("surfaces.aileron.sign", True, "'surfaces.aileron.sign' must be one of 1, -1; got True"),
        ("surfaces.aileron.sign", "+", "'surfaces.aileron.sign' must be one of 1, -1"),
        ("surfaces.aileron.trim_us", 3000, "'surfaces.aileron.trim_us' must be at most 2500"),
        ("surfaces.aileron.throw_us", -400, "'surfaces.aileron.throw_us' must be positive"),
        ("surfaces.aileron.max_deflection_rad", 30,
         "'surfaces.aileron.max_deflection_rad' must be at most 1.5708"),
        ("surfaces.aileron.max_deflection_rad", ".nan",
         "'surfaces.aileron.max_deflection_rad' must be a finite number"),
        ("surfaces.throttle.full_us", 1100, "'surfaces.throttle.full_us' must differ"),
        ("surfaces.throttle.trim_us", 1500, "unknown key 'surfaces.throttle.trim_us'"),
        ("output_unit", "percent", "'output_unit' must be one of pwm_us, normalised"),
        ("axes", "NED", "'axes' must be one of FRD, FLU; got 'NED'"),
        ("airspeed_source", "ground", "'airspeed_source' must be one of true, calibrated"),
        ("mixed", {"output": 5}, "'mixed' must be a list"),
        ("mixed.0.scale", 2, "unknown key 'mixed[0].scale'"),
        ("mixed.0.of_output", 7, "'mixed[0].of_output' is output 7, which no surface uses"),
        ("mixed.0.output", 3, "'mixed[0].output' is output 3, already mapped above"),
        ("mixed.0.factor", 0, "'mixed[0].factor' must not be 0"),
    ],
)
def test_bad_airframes_are_one_line_naming_the_file_and_the_key(tmp_path, key, value, message):
    data = edited(key, value)
    if value == ".nan":  # YAML's NaN, which safe_dump would quote
        path = write(tmp_path, yaml.safe_dump(data).replace("'.nan'", ".nan"))
    else:
        path = write(tmp_path, data)
    with pytest.raises(AirframeError) as error:
        load_airframe(path)
    assert message in str(error.value)
    assert str(error.value).startswith(f"airframe {path}: ")
    assert "\n" not in str(error.value)


@pytest.mark.timeout(10)
def test_normalised_outputs_take_no_pwm_keys(tmp_path):
    data = edited("output_unit", "normalised")
    with pytest.raises(AirframeError, match=r"unknown key 'surfaces\.aileron\.throw_us'"):
        load_airframe(write(tmp_path, data))


@pytest.mark.timeout(10)
def test_unreadable_and_malformed_files(tmp_path):
    with pytest.raises(AirframeError, match="cannot read the file"):
        load_airframe(tmp_path / "missing.yaml")
    with pytest.raises(AirframeError, match="not valid YAML"):
        load_airframe(write(tmp_path, "name: [unclosed"))
    with pytest.raises(AirframeError, match="larger than 16 KiB"):
        load_airframe(write(tmp_path, "#" * (17 * 1024)))


@pytest.mark.timeout(10)
def test_pwm_to_deflection_on_known_values(tmp_path):
    airframe = load_airframe(write(tmp_path, PWM_AIRFRAME))
    # rows: every output at trim (idle); at the upper end point; at the lower end point
    log = outputs_log([0.0, 0.1, 0.2], {
        "output_1": [1500, 1900, 1100],  # aileron: trim 1500, throw 400, 0.4 rad, sign +1
        "output_2": [1520, 2020, 1020],  # elevator: trim 1520, throw 500, 0.5 rad, sign -1
        "output_3": [1100, 1900, 1000],  # throttle: idle 1100, full 1900; below idle: 0
        "output_4": [1480, 1780, 1180],  # rudder: trim 1480, throw 300, 0.3 rad
        "output_5": [1500, 1100, 1900],  # the reversed copy of output_1
    })
    surfaces = surface_deflections(log, airframe)
    assert surfaces.columns == ("aileron", "elevator", "rudder", "throttle")
    np.testing.assert_array_equal(surfaces.times_s, log.streams[OUTPUTS].times_s)
    np.testing.assert_allclose(surfaces.values, [[0.0, 0.0, 0.0, 0.0],
                                                 [0.4, -0.5, 0.3, 1.0],
                                                 [-0.4, 0.5, -0.3, 0.0]], atol=1e-12)
    # halfway between trim and the end: half the deflection
    half = outputs_log([0.0], {"output_1": [1700], "output_2": [1520], "output_3": [1500],
                               "output_4": [1480]})
    assert surface_deflections(half, airframe).values[0, 0] == pytest.approx(0.2)


@pytest.mark.timeout(10)
def test_normalised_outputs_are_scaled(tmp_path):
    data = {"name": "normalised_plane", "output_unit": "normalised", "surfaces": {
        "aileron": {"output": 1, "max_deflection_rad": 0.35, "sign": -1},
        "elevator": {"output": 2, "max_deflection_rad": 0.3, "sign": 1},
        "throttle": {"output": 3}}}
    airframe = load_airframe(write(tmp_path, data))
    log = outputs_log([0.0, 1.0], {"output_1": [0.5, -1.0], "output_2": [-0.5, 1.0],
                                   "output_3": [0.25, 1.2]}, unit="normalised")
    values = surface_deflections(log, airframe).values
    np.testing.assert_allclose(values[:, :2], [[-0.175, -0.15], [0.35, 0.3]])
    assert np.isnan(values[:, 2]).all()  # no rudder in the file
    np.testing.assert_allclose(values[:, 3], [0.25, 1.0])  # throttle clipped to 1


@pytest.mark.timeout(10)
def test_a_log_that_does_not_fit_the_airframe_is_one_line(tmp_path):
    airframe = load_airframe(write(tmp_path, PWM_AIRFRAME))
    short = outputs_log([0.0], {"output_1": [1500], "output_2": [1500], "output_3": [1500]})
    with pytest.raises(ValueError, match=r"has no output_4, which airframe .* maps"):
        surface_deflections(short, airframe)
    normalised = outputs_log([0.0], {"output_1": [0.0]}, unit="normalised")
    with pytest.raises(ValueError, match=r"has normalised outputs, airframe .* maps pwm_us"):
        surface_deflections(normalised, airframe)


@pytest.mark.timeout(10)
def test_mixed_outputs_are_checked_against_the_log(tmp_path):
    airframe = load_airframe(write(tmp_path, PWM_AIRFRAME))
    aileron = np.array([1500.0, 1700.0, 1300.0, 1900.0])
    columns = {"output_1": aileron, "output_2": [1520] * 4, "output_3": [1100] * 4,
               "output_4": [1480] * 4}
    copy_ = outputs_log(np.arange(4.0), {**columns, "output_5": 3000.0 - aileron})
    assert mixed_output_mismatches(copy_, airframe) == []
    # the copy's own value does not change the aileron
    np.testing.assert_allclose(surface_deflections(copy_, airframe).values[:, 0],
                               [0.0, 0.2, -0.2, 0.4])
    not_a_copy = outputs_log(np.arange(4.0), {**columns, "output_5": aileron})
    [line] = mixed_output_mismatches(not_a_copy, airframe)
    assert line.startswith(f"airframe {airframe.path}: in log synthetic.ulg output_5 is not "
                           "-1 x output_1 (off by 200 % of the throw at t = 3.00 s)")
    [line] = mixed_output_mismatches(outputs_log(np.arange(4.0), columns), airframe)
    assert "has no output_5" in line


@pytest.mark.timeout(10)
def test_a_surface_with_two_copies_is_commanded_by_their_vote(tmp_path):
    """ALFA's aileron: output 5, its second servo output 6 and the rudder's mix output 4
    (0.5 x). Each pinned in turn (one at a time) is outvoted; with one copy only, the
    surface's own output is read even when pinned (two cannot tell which is wrong)."""
    data = edited("mixed", [{"output": 5, "of_output": 1, "factor": -1.0},
                            {"output": 6, "of_output": 1, "factor": 0.5}])
    airframe = load_airframe(write(tmp_path, data))
    command_us = np.array([1500.0, 1600.0, 1400.0, 1700.0])  # output 1's intended PWM
    copies = {"output_5": 1500.0 - (command_us - 1500.0),
              "output_6": 1500.0 + 0.5 * (command_us - 1500.0)}
    others = {"output_2": [1520.0] * 4, "output_3": [1100.0] * 4, "output_4": [1480.0] * 4}
    expected_rad = 0.4 * (command_us - 1500.0) / 400.0
    for pinned in ("output_1", "output_5", "output_6"):
        columns = {"output_1": command_us, **copies, **others}
        columns[pinned] = np.full(4, 1500.0)  # a failure holds it at its trim
        log = outputs_log([0.0, 0.1, 0.2, 0.3], dict(sorted(columns.items())))
        aileron = surface_deflections(log, airframe).values[:, 0]
        np.testing.assert_allclose(aileron, expected_rad, atol=1e-12, err_msg=pinned)
        assert mixed_output_mismatches(log, airframe)  # the pinned output is still warned of
    one_copy = load_airframe(write(tmp_path, PWM_AIRFRAME))
    columns = {"output_1": np.full(4, 1500.0), "output_5": copies["output_5"], **others}
    log = outputs_log([0.0, 0.1, 0.2, 0.3], dict(sorted(columns.items())))
    np.testing.assert_allclose(surface_deflections(log, one_copy).values[:, 0], 0.0)
