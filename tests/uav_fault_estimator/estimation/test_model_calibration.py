"""Model calibration: parameters, the fit on a flight of an aircraft that is not its model,
the calibration file, and the recording a calibration reads."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers.flights import calm
from helpers.recordings import write_recording
from helpers.repo import SCRIPTS
from uav_aircraft.flown_aircraft import NOMINAL, FlownAircraft, SensorBias, coefficient_names
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import STATE_CHANNELS
from uav_fault_estimator.chain.offline import sensor_flight
from uav_fault_estimator.estimation.identifiability import (
    AXES,
    MANOEUVRE_FOR_AXIS,
    informing_flights,
    parameter_axis,
    separating_manoeuvres,
)
from uav_fault_estimator.estimation.model_calibration import calibrate
from uav_fault_estimator.estimation.model_file import (
    ModelCalibrationError,
    calibration_dict,
    load_model_calibration,
)
from uav_fault_estimator.estimation.model_parameters import (
    AIRCRAFT_PARAMETERS,
    DEFAULT_PARAMETERS,
    changed,
    model_parameter,
    parameter_list,
    values_of,
)
from uav_fault_estimator.estimation.noise_model import load_noise_calibration
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.recording.project_bag import (
    RecordingError,
    project_typestore,
    sensor_flight_from_recording,
)
from uav_sim.manoeuvres import Manoeuvre
from uav_sim.scenario import SensorSuite, default_scenario_path, load_scenario

# A flown aircraft with more drag, a stiffer pitch and a misaligned alpha vane, and its CG
# 1.5 cm aft and 1 cm low, as measured on the ground
TRUTH = {"CDmin": 8.0, "Cmalpha": 6.0, "angle_of_attack_deg": 0.4}
MEASURED = FlownAircraft(cg_offset_m=(-0.015, 0.0, 0.01))
AEROSONDE = load_vehicle("aerosonde")
FLOWN = dataclasses.replace(MEASURED, coefficients=(("CDmin", 1.08), ("Cmalpha", 1.06)),
                            sensor_bias=SensorBias(angle_of_attack_deg=0.4))
FLIGHT_S = 120.0  # the first leg and the first turn


@pytest.fixture(scope="module")
def flight():
    """The default route in calm air with ideal sensors and air data, of FLOWN."""
    scenario = calm(load_scenario(default_scenario_path()), FLIGHT_S)
    return sensor_flight(dataclasses.replace(
        scenario, aircraft=FLOWN, sensors=SensorSuite(air_data=True, noise=False)))


@pytest.fixture(scope="module")
def calibration(flight):
    return calibrate([flight], tuple(TRUTH), ResidualSettings(), load_noise_calibration(),
                     log=lambda line: None, measured=MEASURED)


def test_a_parameter_change_and_its_value_are_one_another():
    changes = {"CDmin": 10.0, "mass_scale": -3.0, "inertia_y_scale": 5.0, "cg_y_cm": 1.5,
               "airspeed_scale": 2.0, "angle_of_attack_deg": 0.5}
    aircraft = changed(NOMINAL, changes)
    assert dict(aircraft.coefficients) == {"CDmin": pytest.approx(1.10)}
    assert aircraft.mass_scale == pytest.approx(0.97)
    assert aircraft.inertia_scale == pytest.approx((1.0, 1.05, 1.0))
    assert aircraft.cg_offset_m == pytest.approx((0.0, 0.015, 0.0))
    assert aircraft.sensor_bias == SensorBias(airspeed_scale=pytest.approx(1.02),
                                              angle_of_attack_deg=0.5)
    assert values_of(aircraft, tuple(changes)) == pytest.approx(changes)


def test_an_unknown_parameter_is_named():
    with pytest.raises(ValueError, match="unknown model parameter 'CDwing'"):
        model_parameter("CDwing", AEROSONDE)
    for name in DEFAULT_PARAMETERS:
        model_parameter(name, AEROSONDE)


@pytest.mark.timeout(10)
def test_a_parameter_list_names_every_coefficient_at_once():
    names = parameter_list("coefficients, mass_scale", AEROSONDE)
    assert names == (*coefficient_names(AEROSONDE), "mass_scale")
    with pytest.raises(ValueError, match="each parameter once"):
        parameter_list("coefficients, CDmin", AEROSONDE)


@pytest.mark.timeout(120)
def test_the_calibration_finds_how_the_flown_aircraft_differs(calibration):
    """On one calm flight with ideal sensors each parameter is found within 3 posterior
    deviations and close to the truth in absolute terms (0.5 % of a scale, 0.02 deg)."""
    found = dict(zip(calibration.names, calibration.values, strict=True))
    deviation = dict(zip(calibration.names, calibration.posterior_std, strict=True))
    for name, truth in TRUTH.items():
        assert abs(found[name] - truth) <= 3 * deviation[name], (name, found, deviation)
    assert found["CDmin"] == pytest.approx(8.0, abs=0.5)
    assert found["Cmalpha"] == pytest.approx(6.0, abs=0.5)
    assert found["angle_of_attack_deg"] == pytest.approx(0.4, abs=0.02)
    assert calibration.correlations.shape == (3, 3)
    assert np.allclose(np.diag(calibration.correlations), 1.0)


@pytest.mark.timeout(120)
def test_what_was_measured_on_the_ground_is_kept_and_is_the_prior(calibration):
    assert calibration.aircraft.cg_offset_m == MEASURED.cg_offset_m
    assert np.array_equal(calibration.prior_mean, np.zeros(3))  # nothing fitted was measured
    moved = calibrate([], ("cg_x_cm", "CDmin"), ResidualSettings(), load_noise_calibration(),
                      log=lambda line: None, measured=MEASURED)
    # no flight: the prior alone, about what was measured
    assert moved.prior_mean == pytest.approx([-1.5, 0.0])
    assert moved.values == pytest.approx([-1.5, 0.0])


@pytest.mark.timeout(120)
def test_the_calibration_file_gives_the_models_back(calibration, tmp_path):
    noise = tmp_path / "model.noise.yaml"
    noise.write_text("the noise file's existence is what is checked here\n")
    path = tmp_path / "model.yaml"
    path.write_text(yaml.safe_dump(calibration_dict(calibration, "aerosonde", ["one flight"],
                                                    noise.name), sort_keys=False))
    loaded = load_model_calibration(path, "aerosonde")
    assert loaded.noise_file == noise
    assert loaded.aircraft.cg_offset_m == pytest.approx(MEASURED.cg_offset_m)
    assert dict(loaded.aircraft.coefficients) == pytest.approx(dict(
        calibration.aircraft.coefficients))
    assert loaded.aircraft.sensor_bias.angle_of_attack_deg == pytest.approx(
        calibration.aircraft.sensor_bias.angle_of_attack_deg)


def write_calibration(path: Path, **changes) -> Path:
    entries = {"vehicle": "aerosonde", "model_file": "aerosonde.xml",
               "model_sha256": AEROSONDE.model_sha256,
               "aircraft": {"coefficients": {"CDmin": 1.1}}, **changes}
    path.write_text(yaml.safe_dump(entries))
    return path


@pytest.mark.timeout(30)
@pytest.mark.parametrize(("changes", "words"), [
    ({"model_sha256": "0" * 64}, "made for another model file"),
    ({"vehicle": "another_aircraft"}, "made for the vehicle 'another_aircraft', not 'aerosonde'"),
    ({"aircraft": {"coefficients": {"CDwing": 1.1}}}, "unknown key 'aircraft.coefficients.CDwing'"),
    ({"aircraft": {"mass_scale": 3.0}}, "'aircraft.mass_scale'"),
    ({"noise_calibration_file": "nowhere.yaml"}, "does not exist"),
    ({"colour": "red"}, "unknown key 'colour'"),
])
def test_a_calibration_that_cannot_be_used_is_one_line(tmp_path, changes, words):
    path = write_calibration(tmp_path / "model.yaml", **changes)
    with pytest.raises(ModelCalibrationError) as raised:
        load_model_calibration(path, "aerosonde")
    message = str(raised.value)
    assert words in message and str(path) in message and "\n" not in message


@pytest.fixture(scope="module")
def short_flight(flight):
    keep = flight.times_s <= 20.0
    return dataclasses.replace(flight, times_s=flight.times_s[keep],
                               states=flight.states[keep], controls=flight.controls[keep],
                               winds_ned_mps=flight.winds_ned_mps[keep],
                               air_data=flight.air_data[keep])


@pytest.mark.timeout(60)
def test_a_recording_reads_back_as_the_flight(short_flight, tmp_path):
    bag = write_recording(tmp_path / "bag", short_flight)
    read = sensor_flight_from_recording(bag, project_typestore())
    assert np.allclose(read.times_s, short_flight.times_s, rtol=0.0, atol=1e-9)  # stamps: ns
    for field in ("states", "controls", "winds_ned_mps", "air_data"):
        assert np.array_equal(getattr(read, field), getattr(short_flight, field)), field
    assert len(STATE_CHANNELS) == read.states.shape[1]


@pytest.mark.timeout(60)
def test_a_recording_with_a_fault_seeded_is_refused(short_flight, tmp_path):
    bag = write_recording(tmp_path / "bag", short_flight, seeded_pct=5.0)
    with pytest.raises(RecordingError,
                       match=r"not a fault-free flight \(right_wing_lift_loss seeded"):
        sensor_flight_from_recording(bag, project_typestore())


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("arguments", "words"), [
    (["nowhere", "--out", "m.yaml"], "recording nowhere: no such folder"),
    (["nowhere", "--out", "m.yaml", "--parameters", "CDmin,CDwing"],
     "unknown model parameter 'CDwing'"),
    (["nowhere", "--out", "m.yaml", "--measured", "weighed.yaml"],
     "measured aircraft weighed.yaml"),
])
def test_calibrate_model_says_what_is_wrong_in_one_line(tmp_path, arguments, words):
    result = subprocess.run([sys.executable, str(SCRIPTS / "calibrate_model.py"), *arguments],
                            capture_output=True, text=True, timeout=50, cwd=tmp_path)
    assert result.returncode == 2
    assert words in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "m.yaml").exists()



@pytest.mark.timeout(30)
@pytest.mark.parametrize("vehicle", ["aerosonde", "carbon_z"])
def test_every_parameter_has_an_axis_and_a_manoeuvre(vehicle):
    names = parameter_list("coefficients", load_vehicle(vehicle)) + AIRCRAFT_PARAMETERS
    assert {parameter_axis(name) for name in names} == set(AXES)
    assert separating_manoeuvres("Cmalpha", "Cmde") == [MANOEUVRE_FOR_AXIS["pitch"]]
    assert separating_manoeuvres("mass_scale", "Cnr") == [MANOEUVRE_FOR_AXIS["throttle"],
                                                          MANOEUVRE_FOR_AXIS["yaw"]]


@pytest.mark.timeout(120)
def test_steady_sideslips_inform_the_yaw_stiffness_a_level_leg_does_not():
    """Two calm 60 s legs of the model's own aircraft, one with a sideslip doublet (12 deg,
    12 s each way): the yaw stiffness is informed by that one only."""
    leg = dataclasses.replace(calm(load_scenario(default_scenario_path()), 60.0),
                              sensors=SensorSuite(air_data=True, noise=False))
    sideslips = Manoeuvre(10.0, "doublet", "yaw", "attitude", 12.0, step_s=12.0)
    flights = [sensor_flight(leg),
               sensor_flight(dataclasses.replace(leg, manoeuvres=(sideslips,)))]
    calibration = calibrate(flights, ("Cnbeta", "Cnr"), ResidualSettings(),
                            load_noise_calibration(), log=lambda line: None)
    informed = informing_flights(calibration.flight_posterior_std, calibration.prior_std,
                                 ["level", "sideslips"])
    assert informed[0] == ["sideslips"], calibration.flight_posterior_std
