"""What configures the detector: detector_node's settings, which the detector is made from
(self_tuning_detector): the calibration it runs, checked against the airframe flown, the
signatures its alarms name their cause by, the templates learned with them, and the designed
false-alarm rates. The
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
    load_signatures_file,
    signature_features,
    signatures_from,
)
from uav_fault_estimator.detection.templates import (
    DEFAULT_TEMPLATE_FALSE_ALARMS_PER_HOUR,
    FailureTemplates,
    templates_in,
)


@dataclass(frozen=True)
class DetectorSettings:
    """The self-tuning detector's settings: the vehicle, its calibration file and the
    airframe flown (empty: the vehicle's shipped calibration, the vehicle as simulated), and
    the designed false-alarm probability per sample of each self-tuning test and the fast
    and template tests' false alarms per flight hour."""

    vehicle: str = declared_setting(VEHICLE_PARAMETER)
    calibration_file: str = setting(
        "detector calibration YAML (it carries its window, forgetting factor, sample period "
        "and settling time); empty: the vehicle's detector_calibration.yaml", "")
    airframe: str = setting("the airframe flown: the calibration must be of it; empty: the "
                            "vehicle as simulated (<vehicle>_sim)", "")
    signatures_file: str = setting(
        "failure signatures YAML learned with the calibration's channels (which failed part "
        "an alarm names, and the template test's shapes where it holds them); empty: with "
        "the vehicle's shipped calibration its failure_signatures.yaml, else none (an alarm "
        "names the part of its strongest channel; no template test)", "")
    false_alarm_probability: float = setting(
        "designed P_FA per sample of each self-tuning test (GLRT, parameters; eq. 23-25); a "
        "change moves their thresholds", 0.01,
        1e-9, 0.5, live=True)
    fast_false_alarms_per_hour: float = setting(
        "designed false alarms per flight hour of each channel's fast test (window of the "
        "residuals with the calibration's parameters); a change moves its thresholds",
        DEFAULT_FAST_FALSE_ALARMS_PER_HOUR, 1e-3, 100.0, live=True)
    template_false_alarms_per_hour: float = setting(
        "designed false alarms per flight hour of each template of the template test (a "
        "failure's learned shape over the whitened residuals); a change moves its thresholds",
        DEFAULT_TEMPLATE_FALSE_ALARMS_PER_HOUR, 1e-3, 100.0, live=True)


def detector_calibration(settings: DetectorSettings) -> Calibration:
    """The calibration the settings name, checked against the airframe flown; ValueError
    with one line naming the file."""
    return read_calibration(
        settings.calibration_file or str(shipped_calibration_path(settings.vehicle)),
        settings.airframe or simulated_airframe(settings.vehicle))


def learned_failures(settings: DetectorSettings, calibration: Calibration
                     ) -> tuple[FailureSignatures | None, FailureTemplates | None]:
    """The signatures and templates of the signatures file the settings name (ValueError
    with one line when it cannot be read or was learned with other channels than the
    calibration's); without one, the vehicle's shipped file where the calibration is its
    shipped one (it was learned with it), else none. The file is read once."""
    path = Path(settings.signatures_file or load_vehicle(settings.vehicle)
                .failure_signatures_file)
    if not settings.signatures_file and (settings.calibration_file or not path.is_file()):
        return None, None
    data = load_signatures_file(path)
    signatures = signatures_from(data, path)
    if signatures.features != signature_features(calibration):
        if not settings.signatures_file:
            return None, None
        raise ValueError(f"signatures file {path} is over {', '.join(signatures.features)}, "
                         "the calibration's signatures over "
                         f"{', '.join(signature_features(calibration))}")
    return signatures, templates_in(data, path)


def self_tuning_detector(settings: DetectorSettings) -> SelfTuningDetector:
    """The detector the settings describe: their calibration, signatures and templates, at
    their false-alarm probability and fast-test and template-test rates."""
    calibration = detector_calibration(settings)
    signatures, templates = learned_failures(settings, calibration)
    return SelfTuningDetector(calibration, settings.false_alarm_probability,
                              settings.fast_false_alarms_per_hour, signatures, templates,
                              settings.template_false_alarms_per_hour)
