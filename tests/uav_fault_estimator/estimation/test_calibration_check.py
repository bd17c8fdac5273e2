"""The model calibration's check: an aircraft whose payload sits off the centre line,
calibrated without the CG among its parameters, is warned of with the channel it rolls and
the parameter that would take it; calibrated with them, it fits and is not. calibrate_model.py
prints the warnings and ends on a line saying the check failed, with status 3 (with --strict
it writes nothing and exits 1); given the CG as measured on the ground, it fits, and its last
line says the check passed."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np
import pytest
import yaml
from helpers.flights import calm
from helpers.recordings import write_recording
from helpers.repo import SCRIPTS
from uav_aircraft.flown_aircraft import FlownAircraft
from uav_fault_estimator.chain.offline import sensor_flight
from uav_fault_estimator.estimation.calibration_check import (
    MAX_PRIOR_DEVIATIONS,
    check_calibration,
    regimes,
)
from uav_fault_estimator.estimation.model_calibration import calibrate
from uav_fault_estimator.estimation.noise_model import load_noise_calibration
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_sim.scenario import SensorSuite, default_scenario_path, load_scenario

FLOWN = FlownAircraft(cg_offset_m=(0.0, 0.02, 0.0))  # 2 cm right of the centre line
FLIGHT_S = 120.0  # the first leg and the first turn
WITHOUT_CG = ("CL0", "CLalpha", "CDmin", "Cm0", "Cmalpha", "Clp", "Clda")


@pytest.fixture(scope="module")
def flight():
    """The default route in calm air with ideal sensors and air data, of FLOWN."""
    scenario = calm(load_scenario(default_scenario_path()), FLIGHT_S)
    return sensor_flight(dataclasses.replace(
        scenario, aircraft=FLOWN, sensors=SensorSuite(air_data=True, noise=False)))


def calibrated(flight, names):
    return calibrate([flight], names, ResidualSettings(), load_noise_calibration(),
                     log=lambda line: None)


@pytest.mark.timeout(300)
def test_an_unfitted_cg_offset_is_warned_of_and_a_fitted_one_is_not(flight):
    noise = load_noise_calibration()
    without = check_calibration(calibrated(flight, WITHOUT_CG), [flight], noise)
    print("\n".join(w.text for w in without))
    subjects = {w.subject for w in without}
    assert {"angular_x straight", "angular_x turning"} & subjects, subjects
    remainder = next(w for w in without if w.subject.startswith("angular_x"))
    assert "cg_y_cm" in remainder.text
    # the roll parameters pushed far to stand in for it
    assert {"Clp", "Clda"} & subjects, subjects

    fitted = calibrated(flight, (*WITHOUT_CG, "cg_y_cm"))
    with_cg = check_calibration(fitted, [flight], noise)
    print("\n".join(w.text for w in with_cg))
    assert with_cg == []
    found = dict(zip(fitted.names, fitted.values, strict=True))
    assert found["cg_y_cm"] == pytest.approx(2.0, abs=0.2)
    assert all(abs(v) <= MAX_PRIOR_DEVIATIONS * p
               for v, p in zip(fitted.values, fitted.prior_std, strict=True))


@pytest.mark.timeout(300)
def test_the_flight_regimes_are_told_apart(flight):
    labels = regimes(flight, flight.times_s)
    roll = np.abs(flight.states[:, 3])
    assert set(labels) <= {"straight", "turning", "climbing"}
    assert (labels[roll > np.radians(10.0)] == "turning").all()
    assert (labels == "turning").any() and (labels == "straight").any()


@pytest.mark.timeout(300)
def test_calibrate_model_warns_and_strict_writes_nothing(flight, tmp_path):
    bag = write_recording(tmp_path / "bag", flight)
    command = [sys.executable, str(SCRIPTS / "calibrate_model.py"), str(bag), "--out",
               str(tmp_path / "model.yaml"), "--parameters", ",".join(WITHOUT_CG),
               "--workers", "0", "--no-progress"]
    strict = subprocess.run([*command, "--strict"], capture_output=True, text=True,
                            timeout=250)
    assert strict.returncode == 1, strict.stderr
    assert "WARN angular_x keeps a mean" in strict.stdout and "cg_y_cm" in strict.stdout
    assert "--strict" in strict.stderr and len(strict.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "model.yaml").exists()
    lenient = subprocess.run(command, capture_output=True, text=True, timeout=250)
    assert lenient.returncode == 3, lenient.stderr  # written, but the check warned
    assert "WARN angular_x keeps a mean" in lenient.stdout
    warnings = lenient.stdout.count("\nWARN ")
    assert lenient.stdout.splitlines()[-1].startswith(
        f"check failed: {warnings} warnings (the WARN lines above); {tmp_path / 'model.yaml'} "
        "and model.noise.yaml written all the same")
    assert (tmp_path / "model.yaml").exists()
    # the payload's CG weighed on the ground: the same fit then fits, and the model has it
    weighed = tmp_path / "weighed.yaml"
    weighed.write_text(yaml.safe_dump({"aircraft": FLOWN.to_dict()}))
    measured = subprocess.run([*command, "--measured", str(weighed), "--strict"],
                              capture_output=True, text=True, timeout=250)
    assert measured.returncode == 0, measured.stdout + measured.stderr
    assert measured.stdout.splitlines()[-1] == (
        f"check passed: the model fits the flights; {tmp_path / 'model.yaml'} and "
        "model.noise.yaml written")
    model = yaml.safe_load((tmp_path / "model.yaml").read_text())
    assert model["aircraft"]["cg_offset_m"] == pytest.approx(list(FLOWN.cg_offset_m))
