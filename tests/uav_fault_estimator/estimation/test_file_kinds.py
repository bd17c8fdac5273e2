"""A calibration or model file given a file of another kind (a scenario, another
calibration: the YAML files a user holds) is refused in one line saying what the file is
expected to be and what it holds; the shipped files of the right kind read."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
import yaml
from uav_aircraft.vehicles import load_vehicle
from uav_fault_estimator.detection.calibration_file import (
    read_calibration,
    shipped_calibration_path,
)
from uav_fault_estimator.estimation.model_file import load_model_calibration
from uav_fault_estimator.estimation.noise_model import load_noise_calibration, shipped_noise_path
from uav_sim.paths import scenarios_dir

SCENARIO = scenarios_dir() / "default.yaml"
# A scenario that shares a key (`vehicle`) with the calibrations
CARBON_Z_SCENARIO = scenarios_dir() / "carbon_z_default.yaml"
NOISE_EXPECTED = ("not a noise calibration (scripts/calibrate_estimator.py's file, a "
                  "vehicle's residual_noise.yaml), whose keys are vehicle, air_data, "
                  "pitot, filtered_wind")
DETECTOR_EXPECTED = ("not a detector calibration (scripts/calibrate_detector.py's or "
                     "screen_logs.py calibrate's file, a vehicle's detector_calibration.yaml), "
                     "whose keys are airframe, reference_airspeed_mps, sample_period_s, "
                     "forgetting_factor, window, settle_s, parameter_deviation_weibull, channels")
MODEL_EXPECTED = ("not a model calibration (scripts/calibrate_model.py's file), whose keys are "
                  "vehicle, model_file, model_sha256, aircraft")


def model_calibration(folder: Path) -> Path:
    """A model calibration of the Aerosonde as calibrate_model.py lays it out."""
    path = folder / "model.yaml"
    path.write_text(yaml.safe_dump({
        "vehicle": "aerosonde", "model_file": "aerosonde.xml",
        "model_sha256": load_vehicle("aerosonde").model_sha256,
        "aircraft": {"coefficients": {"CDmin": 1.1}}}))
    return path


# kind -> (reader, the prefix of its lines, what it says such a file is)
READERS: dict[str, tuple[Callable[[Path], object], str, str]] = {
    "noise": (lambda path: load_noise_calibration(path, "aerosonde"), "noise calibration",
              NOISE_EXPECTED),
    "detector": (lambda path: read_calibration(str(path)), "calibration file",
                 DETECTOR_EXPECTED),
    "model": (lambda path: load_model_calibration(path, "aerosonde"), "model calibration",
              MODEL_EXPECTED),
}


@pytest.mark.timeout(10)
def test_a_scenario_given_as_the_noise_calibration_is_said_to_be_one():
    with pytest.raises(ValueError) as refused:
        load_noise_calibration(SCENARIO, "aerosonde")
    assert str(refused.value) == (
        f"noise calibration {SCENARIO}: {NOISE_EXPECTED}; this file holds the keys name, "
        "duration_s, seed, initial, waypoints_ne_m, guidance, wind, sensors, faults")


OTHERS = ("scenario", "carbon_z_scenario", "noise", "detector", "model", "empty", "list")


@pytest.mark.timeout(30)
@pytest.mark.parametrize(("kind", "other"), [(kind, other) for kind in READERS
                                             for other in OTHERS if other != kind])
def test_a_file_of_another_kind_is_one_line_saying_what_was_expected_and_found(
        kind, other, tmp_path):
    files = {"scenario": lambda: SCENARIO, "carbon_z_scenario": lambda: CARBON_Z_SCENARIO,
             "noise": shipped_noise_path, "detector": shipped_calibration_path,
             "model": lambda: model_calibration(tmp_path)}
    if other in ("empty", "list"):
        path = tmp_path / f"{other}.yaml"
        path.write_text("" if other == "empty" else "- 1\n- 2\n")
    else:
        path = files[other]()
    read, prefix, expected = READERS[kind]
    with pytest.raises(ValueError) as refused:
        read(path)
    message = str(refused.value)
    print(message)
    assert "\n" not in message
    assert message.startswith(f"{prefix} {path}: ")
    if kind == "model" and other in ("empty", "list"):  # the strict reader's own line
        assert message.endswith("'the file' must be a mapping, got "
                                + ("NoneType" if other == "empty" else "list"))
        return
    data = yaml.safe_load(path.read_text())
    found = {"empty": "nothing", "list": "a list, not a mapping"}.get(
        other, "the keys " + ", ".join(map(str, data or {})))
    assert message == f"{prefix} {path}: {expected}; this file holds {found}"


@pytest.mark.timeout(30)
def test_the_files_of_the_right_kind_read(tmp_path):
    assert set(load_noise_calibration(shipped_noise_path(), "aerosonde").variances) == {
        "air_data", "pitot", "filtered_wind"}
    assert read_calibration(str(shipped_calibration_path())).airframe == "aerosonde_sim"
    assert load_model_calibration(model_calibration(tmp_path), "aerosonde").noise_file is None
