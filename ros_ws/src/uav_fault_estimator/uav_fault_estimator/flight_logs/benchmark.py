"""The detector benchmarked on labelled flights (scripts/alfa_benchmark.py): each flight
screened with a calibration that never saw it, held against its ground truth
(evaluation.py). No ROS here.

A calibration learns from the fault-free parts of flights: a flight without failure whole,
a failure flight up to its onset less a margin (the last seconds before an onset may already
carry the injection's preparation, and are never needed). Leave one flight out: each
labelled flight is screened with the calibration from every other flight's fault-free part;
or one set of flights calibrates and another is screened.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from uav_fault_estimator.detection.calibration import Calibration
from uav_fault_estimator.detection.detector import DetectorFlight, run_detector
from uav_fault_estimator.flight_logs.evaluation import FlightOutcome, flight_outcome
from uav_fault_estimator.flight_logs.ground_truth import FlightTruth
from uav_fault_estimator.flight_logs.resample import DetectorInputs

# Seconds before an onset left out of a calibration (the module's docstring).
ONSET_MARGIN_S = 5.0


@dataclass(frozen=True)
class LabelledFlight:
    """A flight on the detector's grid (inputs) with its name and ground truth."""

    name: str
    inputs: DetectorInputs
    truth: FlightTruth


def fault_free_part(flight: LabelledFlight, margin_s: float = ONSET_MARGIN_S
                    ) -> DetectorFlight | None:
    """The flight's samples a calibration may learn from: all of a flight without failure,
    those up to margin_s [s] before the onset of a failure flight; None when none are left."""
    inputs = flight.inputs
    onset = flight.truth.onset_stamp_s
    if onset is None:
        return inputs.flight
    kept = inputs.start_stamp_s + inputs.times_s < onset - margin_s
    if not kept.any():
        return None
    return DetectorFlight(*(None if column is None else np.asarray(column)[kept]
                            for column in inputs.flight))


Calibrate = Callable[[Sequence[DetectorFlight]], Calibration]


def screened(flight: LabelledFlight, calibration: Calibration,
             false_alarm_probability: float) -> FlightOutcome:
    """One flight screened with calibration and held against its truth."""
    samples = run_detector(calibration, flight.inputs.flight, false_alarm_probability)
    return flight_outcome(flight.name, flight.truth, samples, calibration.channel_names,
                          flight.inputs.start_stamp_s)


def leave_one_out(flights: Sequence[LabelledFlight], calibrate: Calibrate,
                  false_alarm_probability: float,
                  margin_s: float = ONSET_MARGIN_S) -> list[FlightOutcome]:
    """Each flight screened with calibrate(the fault-free parts of all the others)."""
    parts = [fault_free_part(flight, margin_s) for flight in flights]
    outcomes = []
    for k, flight in enumerate(flights):
        others = [part for j, part in enumerate(parts) if j != k and part is not None]
        outcomes.append(screened(flight, calibrate(others), false_alarm_probability))
    return outcomes


def calibrated_on(calibration_flights: Sequence[LabelledFlight],
                  flights: Sequence[LabelledFlight], calibrate: Calibrate,
                  false_alarm_probability: float,
                  margin_s: float = ONSET_MARGIN_S) -> list[FlightOutcome]:
    """Every flight screened with one calibration from calibration_flights' fault-free parts."""
    parts = [fault_free_part(flight, margin_s) for flight in calibration_flights]
    calibration = calibrate([part for part in parts if part is not None])
    return [screened(flight, calibration, false_alarm_probability) for flight in flights]
