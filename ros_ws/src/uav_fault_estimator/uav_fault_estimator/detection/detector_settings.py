"""What configures the detector: detector_node's settings, which the detector is made from
(self_tuning_detector): the calibration it runs, checked against the airframe flown, the
signatures its alarms name their cause by, and the designed false-alarm rates. The
calibration carries what it was made with (sample period, forgetting factor, GLRT window,
settling time: calibration.Calibration), so no setting restates it. Each field is the
detector_node parameter of its name, declared here once with its default, range and meaning
(uav_common.settings). No ROS here."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from uav_aircraft.vehicle_parameter import VEHICLE_PARAMETER
from uav_aircraft.vehicles import load_vehicle
from uav_common.settings import declared_setting, setting

from uav_fault_estimator.detection.calibration import Calibration, simulated_airframe
from uav_fault_estimator.detection.calibration_file import (
    read_calibration,
    shipped_calibration_path,
)
from uav_fault_estimator.detection.detector import (
    DEFAULT_FAST_FALSE_ALARMS_PER_HOUR,
    SelfTuningDetector,
)
from uav_fault_estimator.detection.signatures import (
    FailureSignatures,
    read_signatures,
    signature_features,
)


@dataclass(frozen=True)
class DetectorSettings:
    """The self-tuning detector's settings: the vehicle, its calibration file and the
    airframe flown (empty: the vehicle's shipped calibration, the vehicle as simulated), and
    the designed false-alarm probability per sample of each self-tuning test and the fast
    test's false alarms per flight hour."""

    vehicle: str = declared_setting(VEHICLE_PARAMETER)
    calibration_file: str = setting(
        "detector calibration YAML (it carries its window, forgetting factor, sample period "
        "and settling time); empty: the vehicle's detector_calibration.yaml", "")
    airframe: str = setting("the airframe flown: the calibration must be of it; empty: the "
                            "vehicle as simulated (<vehicle>_sim)", "")
    signatures_file: str = setting(
        "failure signatures YAML learned with the calibration's channels (which failed part "
        "an alarm names); empty: with the vehicle's shipped calibration its "
        "failure_signatures.yaml, else none (an alarm names the part of its strongest "
        "channel)", "")
    false_alarm_probability: float = setting(
        "designed P_FA per sample of each self-tuning test (GLRT, parameters; eq. 23-25); a "
        "change moves their thresholds", 0.01,
        1e-9, 0.5, live=True)
    fast_false_alarms_per_hour: float = setting(
        "designed false alarms per flight hour of each channel's fast test (window of the "
        "residuals with the calibration's parameters); a change moves its thresholds",
        DEFAULT_FAST_FALSE_ALARMS_PER_HOUR, 1e-3, 100.0, live=True)


def detector_calibration(settings: DetectorSettings) -> Calibration:
    """The calibration the settings name, checked against the airframe flown; ValueError
    with one line naming the file."""
    return read_calibration(
        settings.calibration_file or str(shipped_calibration_path(settings.vehicle)),
        settings.airframe or simulated_airframe(settings.vehicle))


def detector_signatures(settings: DetectorSettings, calibration: Calibration
                        ) -> FailureSignatures | None:
    """The signatures the settings name (ValueError with one line when that file cannot be
    read or was learned with other channels than the calibration's); without one, the
    vehicle's shipped signatures where the calibration is its shipped one (they were
    learned with it), else None."""
    if settings.signatures_file:
        signatures = read_signatures(Path(settings.signatures_file))
        if signatures.features != signature_features(calibration):
            raise ValueError(f"signatures file {settings.signatures_file} is over "
                             f"{', '.join(signatures.features)}, the calibration's "
                             f"signatures over {', '.join(signature_features(calibration))}")
        return signatures
    shipped = load_vehicle(settings.vehicle).failure_signatures_file
    if settings.calibration_file or not shipped.is_file():
        return None
    signatures = read_signatures(shipped)
    return signatures if signatures.features == signature_features(calibration) else None


def self_tuning_detector(settings: DetectorSettings) -> SelfTuningDetector:
    """The detector the settings describe: their calibration and signatures, at their
    false-alarm probability and fast-test rate."""
    calibration = detector_calibration(settings)
    return SelfTuningDetector(calibration, settings.false_alarm_probability,
                              settings.fast_false_alarms_per_hour,
                              detector_signatures(settings, calibration))
