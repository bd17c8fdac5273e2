"""What configures the detector: detector_node's settings, which the detector is made from
(self_tuning_detector): the calibration it runs, checked against the airframe flown, and the
designed false-alarm probability. The calibration carries what it was made with (sample
period, forgetting factor, GLRT window, settling time: calibration.Calibration), so no
setting restates it. Each field is the detector_node parameter of its name, declared here
once with its default, range and meaning (uav_common.settings). No ROS here."""

from __future__ import annotations

from dataclasses import dataclass

from uav_aircraft.vehicle_parameter import VEHICLE_PARAMETER
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


def self_tuning_detector(settings: DetectorSettings) -> SelfTuningDetector:
    """The detector the settings describe: their calibration, at their false-alarm
    probability and fast-test rate."""
    return SelfTuningDetector(detector_calibration(settings), settings.false_alarm_probability,
                              settings.fast_false_alarms_per_hour)
