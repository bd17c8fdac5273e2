"""The detector's calibration file: YAML of Calibration's fields (the layout of a vehicle
folder's detector_calibration.yaml), written by scripts/calibrate_detector.py and read by
detector_node, checked against the airframe flown. No ROS here."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from uav_aircraft.vehicles import DEFAULT_VEHICLE, load_vehicle
from uav_common.strict_yaml import kind_mismatch

from uav_fault_estimator.detection.calibration import (
    SIMULATED_AIRFRAME,
    Calibration,
    ChannelCalibration,
    FastTestCalibration,
)
from uav_fault_estimator.detection.change_detection import Weibull
from uav_fault_estimator.detection.generators import GENERATORS, checked_generators

# What a detector calibration file is, for the line that refuses a file of another kind
DETECTOR_CALIBRATION = ("a detector calibration (scripts/calibrate_detector.py's or "
                        "screen_logs.py calibrate's file, a vehicle's detector_calibration.yaml)")
# The keys every such file has (calibration_to_dict's)
CALIBRATION_KEYS = ("airframe", "reference_airspeed_mps", "sample_period_s", "forgetting_factor",
                    "window", "settle_s", "parameter_deviation_weibull", "channels")


def calibration_to_dict(calibration: Calibration) -> dict[str, Any]:
    """The calibration as the file's mapping (YAML-ready lists and numbers)."""
    return {
        "airframe": calibration.airframe,
        "reference_airspeed_mps": calibration.reference_airspeed_mps,
        "sample_period_s": calibration.sample_period_s,
        "forgetting_factor": calibration.forgetting_factor,
        "window": calibration.window,
        "settle_s": calibration.settle_s,
        "fast_window": calibration.fast_window,
        "fast_reference": calibration.fast_reference,
        "parameter_deviation_weibull": _weibull_dict(calibration.parameter),
        "channels": {name: {
            "parameters": list(GENERATORS[name].parameters),
            "theta0": c.theta0.tolist(), "p0": c.p0.tolist(),
            "parameter_mean": c.parameter_mean.tolist(),
            "parameter_std": c.parameter_std.tolist(),
            "parameter_slope_per_mps": (None if c.parameter_slope is None
                                        else c.parameter_slope.tolist()),
            "glrt_weibull": _weibull_dict(c.glrt),
            "fast_residual_std": c.fast.residual_std,
            "fast_weibull": _weibull_dict(c.fast.statistic),
        } for name, c in calibration.channels.items()},
    }


def calibration_from_dict(data: Mapping[str, Any]) -> Calibration:
    """From calibration_to_dict's layout; KeyError or ValueError on a malformed one."""
    reference = data["reference_airspeed_mps"]
    if min(int(data["fast_window"]), int(data["fast_reference"])) < 1:
        raise ValueError(f"fast_window {data['fast_window']}, fast_reference "
                         f"{data['fast_reference']}: at least 1 sample each")
    channels = {}
    for name in checked_generators(tuple(data["channels"])):
        c = data["channels"][name]
        n = len(GENERATORS[name].parameters)
        if list(c["parameters"]) != list(GENERATORS[name].parameters):
            raise ValueError(f"channel {name}: parameters must be "
                             f"{', '.join(GENERATORS[name].parameters)}")
        arrays = [np.array(c[key], dtype=float) for key in
                  ("theta0", "p0", "parameter_mean", "parameter_std")]
        slope = c["parameter_slope_per_mps"]
        if [a.shape for a in arrays] != [(n,), (n, n), (n,), (n,)] or (
                (slope is None) != (reference is None)) or (
                slope is not None and len(slope) != n):
            raise ValueError(f"channel {name}: arrays must be {n}, {n}x{n}, {n}, {n}, and "
                             f"a slope of {n} exactly when scheduled on airspeed")
        fast = FastTestCalibration(float(c["fast_residual_std"]), Weibull(**c["fast_weibull"]))
        if not fast.residual_std > 0.0:
            raise ValueError(f"channel {name}: fast_residual_std must be > 0")
        channels[name] = ChannelCalibration(
            *arrays, glrt=Weibull(**c["glrt_weibull"]), fast=fast,
            parameter_slope=None if slope is None else np.array(slope, dtype=float))
    return Calibration(float(data["sample_period_s"]), float(data["forgetting_factor"]),
                       int(data["window"]), float(data["settle_s"]), channels,
                       Weibull(**data["parameter_deviation_weibull"]), str(data["airframe"]),
                       None if reference is None else float(reference), int(data["fast_window"]),
                       int(data["fast_reference"]))


def _weibull_dict(distribution: Weibull) -> dict[str, float]:
    return {"scale": distribution.scale, "shape": distribution.shape}



def shipped_calibration_path(vehicle: str = DEFAULT_VEHICLE) -> Path:
    """The vehicle's detector_calibration.yaml (scripts/calibrate_detector.py)."""
    return load_vehicle(vehicle).detector_calibration_file


def surface_calibration_path(vehicle: str = DEFAULT_VEHICLE) -> Path:
    """The vehicle's calibration of the paper's three generators (roll, pitch, yaw), for
    flights and logs without the autopilot's setpoints (scripts/calibrate_detector.py
    --generators roll,pitch,yaw)."""
    return load_vehicle(vehicle).surface_detector_calibration_file


def read_calibration(path: str, airframe: str = SIMULATED_AIRFRAME) -> Calibration:
    """The calibration file (empty path: the default vehicle's), checked against the airframe
    flown, with the sample period, forgetting factor, window and settling time it was made
    with; ValueError with one line naming the file."""
    file = Path(path) if path else shipped_calibration_path()
    try:
        data = yaml.safe_load(file.read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
        raise ValueError(f"calibration file {file}: {type(error).__name__}: {error}") from None
    mismatch = kind_mismatch(data, CALIBRATION_KEYS, DETECTOR_CALIBRATION)
    if mismatch:
        raise ValueError(f"calibration file {file}: {mismatch}")
    if "fast_window" not in data:
        raise ValueError(f"calibration file {file} holds no fast test (fast_window, "
                         "fast_reference, each channel's fast_*): calibrate again "
                         "(scripts/calibrate_detector.py, screen_logs.py calibrate)")
    try:
        calibration = calibration_from_dict(data)
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"calibration file {file}: {type(error).__name__}: {error}") from None
    if calibration.airframe != airframe:
        raise ValueError(
            f"calibration file {file} is for the airframe '{calibration.airframe}', not "
            f"'{airframe}': calibrate from fault-free flights of '{airframe}' "
            "(scripts/screen_logs.py)")
    return calibration

