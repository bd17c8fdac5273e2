"""A model calibration file: what scripts/calibrate_model.py writes and residual_node reads.

    vehicle: <vehicle>              # the aircraft it was made for: refused for any other
    model_file: <vehicle>.xml
    model_sha256: <hex>             # the vehicle XML it was made for: refused for any other
    aircraft: {...}                 # as a scenario's aircraft block: what the models load
    noise_calibration_file: NAME    # optional: mhe_node's noise from the same flights
    parameters: {NAME: {unit, value, prior, prior_std, posterior_std}}   # what was found
    worst_correlations: [...]       # what the flights could not separate
    fit: {...}                      # steps, reduced chi-square, flights

Only vehicle, model_sha256, aircraft and noise_calibration_file are used; the rest says how the
calibration came about. No ROS here.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from uav_aircraft.flown_aircraft import FlownAircraft, read_aircraft
from uav_aircraft.vehicles import load_vehicle
from uav_common.strict_yaml import FileKind, kind_mismatch, load_yaml

from uav_fault_estimator.estimation.model_calibration import (
    ModelCalibration,
)

MODEL_KEY = "model"  # residual_node's /diagnostics key: its calibration file, or the shipped model


def shipped_model(vehicle: str) -> str:
    """What residual_node's copies load without a model calibration, in words."""
    return f"{load_vehicle(vehicle).model_file.name} as shipped"


class ModelCalibrationError(ValueError):
    """A model calibration file that cannot be used (one line: which and why)."""


MODEL_CALIBRATION_FILE = FileKind("model calibration", ModelCalibrationError, 64 * 1024,
                                  "calibrate_model.py writes about 3 kB")
# The keys every model calibration has, and what such a file is (for the line that refuses
# a file of another kind)
MODEL_CALIBRATION_KEYS = ("vehicle", "model_file", "model_sha256", "aircraft")
MODEL_CALIBRATION = "a model calibration (scripts/calibrate_model.py's file)"


MEASURED_AIRCRAFT_FILE = FileKind("measured aircraft", ModelCalibrationError, 64 * 1024,
                                  "an aircraft block is a few hundred bytes")


def load_measured_aircraft(path: str | Path, vehicle: str) -> FlownAircraft:
    """What was measured of the vehicle on the ground (`aircraft:` as a scenario's block,
    for instance its cg_offset_m from a balance and inertia_scale from a pendulum); a
    ModelCalibrationError (one line) when it cannot be read or is malformed."""
    reader = load_yaml(MEASURED_AIRCRAFT_FILE, Path(path))
    reader.check_keys({"aircraft"})
    return read_aircraft(reader.child("aircraft"), load_vehicle(vehicle))


@dataclass(frozen=True)
class CalibratedModel:
    """What a model calibration file gives: the aircraft the models load, and the noise
    calibration made on the same flights (None: the shipped one)."""

    aircraft: FlownAircraft
    noise_file: Path | None


def calibration_dict(calibration: ModelCalibration, vehicle: str, flights: list[str],
                     noise_file: str | None) -> dict:
    """The file's mapping (module docstring), in its key order."""
    model = load_vehicle(vehicle)
    entries = {
        "vehicle": vehicle,
        "model_file": model.model_file.name,
        "model_sha256": model.model_sha256,
        "aircraft": calibration.aircraft.to_dict(),
    }
    if noise_file:
        entries["noise_calibration_file"] = noise_file
    entries["parameters"] = {
        name: {"unit": unit, "value": round(float(value), 4), "prior": round(float(mean), 4),
               "prior_std": float(prior), "posterior_std": round(float(posterior), 4)}
        for name, unit, value, mean, prior, posterior in zip(
            calibration.names, calibration.units, calibration.values, calibration.prior_mean,
            calibration.prior_std, calibration.posterior_std, strict=True)}
    entries["worst_correlations"] = [
        {"pair": [first, second], "correlation": round(value, 3)}
        for first, second, value in calibration.worst_correlations()]
    entries["fit"] = {"gauss_newton_steps": calibration.steps,
                      "reduced_chi_square": round(calibration.reduced_chi_square, 4),
                      "flights": flights}
    return entries


def load_model_calibration(path: str | Path, vehicle: str) -> CalibratedModel:
    """Read a model calibration file for the vehicle; ModelCalibrationError (one line) when
    it cannot be read, is malformed, or was made for another vehicle or another version of
    its XML than the one shipped."""
    path = Path(path)
    reader = load_yaml(MODEL_CALIBRATION_FILE, path)
    mismatch = kind_mismatch(reader.data, MODEL_CALIBRATION_KEYS, MODEL_CALIBRATION)
    if mismatch:
        reader.fail(mismatch)
    reader.check_keys(set(MODEL_CALIBRATION_KEYS),
                      {"noise_calibration_file", "parameters", "worst_correlations", "fit"})
    if reader.text("vehicle") != vehicle:
        reader.fail(f"made for the vehicle {reader.data['vehicle']!r}, not {vehicle!r}")
    model = load_vehicle(vehicle)
    if reader.text("model_sha256") != model.model_sha256:
        reader.fail(f"made for another model file ({reader.data['model_file']!r} with "
                    f"SHA-256 {str(reader.data['model_sha256'])[:12]}...) than "
                    f"{model.model_file} ({model.model_sha256[:12]}...): recalibrate")
    noise_file = None
    if "noise_calibration_file" in reader.data:
        noise_file = path.parent / reader.text("noise_calibration_file")
        if not noise_file.is_file():
            reader.fail(f"'noise_calibration_file' {noise_file} does not exist")
    return CalibratedModel(read_aircraft(reader.child("aircraft"), model), noise_file)
