"""The detector benchmarked on labelled flights (scripts/alfa_benchmark.py): each flight
screened with a calibration that never saw it, held against its ground truth
(evaluation.py). No ROS here.

A calibration learns from the fault-free parts of flights: a flight without failure whole,
a failure flight up to its onset less a margin (the last seconds before an onset may already
carry the injection's preparation, and are never needed). Leave one flight out: each
labelled flight is screened with the calibration from every other flight's fault-free part;
leave one day out: each day's flights with the calibration from the other days' flights
(what a new day brings: weather, trims, sensor offsets, that no flight of it taught); or one
set of flights calibrates and another is screened.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

import numpy as np

from uav_fault_estimator.detection.calibration import Calibration
from uav_fault_estimator.detection.detector import DetectorFlight, DetectorSample, run_detector
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


def fault_free(stamps_s: np.ndarray, truth: FlightTruth,
               margin_s: float = ONSET_MARGIN_S) -> np.ndarray:
    """Which samples, at stamps_s (K,) [s, the log's clock], a calibration may learn from:
    all of a flight without failure, those up to margin_s [s] before the onset of a failure
    flight."""
    if truth.onset_stamp_s is None:
        return np.ones(np.shape(stamps_s), dtype=bool)
    return np.asarray(stamps_s) < truth.onset_stamp_s - margin_s


def fault_free_part(flight: LabelledFlight, margin_s: float = ONSET_MARGIN_S
                    ) -> DetectorFlight | None:
    """The flight's samples a calibration may learn from (fault_free); None when none are
    left."""
    inputs = flight.inputs
    if flight.truth.onset_stamp_s is None:
        return inputs.flight
    kept = fault_free(inputs.start_stamp_s + inputs.times_s, flight.truth, margin_s)
    if not kept.any():
        return None
    return DetectorFlight(*(None if column is None else np.asarray(column)[kept]
                            for column in inputs.flight))


Calibrate = Callable[[Sequence[DetectorFlight]], Calibration]
# (screened, calibration): indices of the flights screened together, of those calibrating
Fold = tuple[list[int], list[int]]


def flight_day(start_stamp_s: float) -> str:
    """The UTC date (YYYY-MM-DD) of a log that starts at start_stamp_s [s, UNIX time]:
    flights of one day share its weather, its airframe's state and its sensors' offsets."""
    start = datetime.fromtimestamp(start_stamp_s, tz=UTC)
    return start.date().isoformat()


def leave_out_folds(groups: Sequence[str]) -> list[Fold]:
    """Each group (by flight its name, or its day) screened with what the other groups
    calibrate, in the order the groups first appear."""
    return [([k for k, g in enumerate(groups) if g == group],
             [k for k, g in enumerate(groups) if g != group])
            for group in dict.fromkeys(groups)]


# seen(flight, calibration, samples): told of every flight screened (to draw it, say)
Seen = Callable[[LabelledFlight, Calibration, list[DetectorSample]], None]


def screened(flight: LabelledFlight, calibration: Calibration,
             false_alarm_probability: float, seen: Seen | None = None) -> FlightOutcome:
    """One flight screened with calibration and held against its truth."""
    samples = run_detector(calibration, flight.inputs.flight, false_alarm_probability)
    if seen is not None:
        seen(flight, calibration, samples)
    return flight_outcome(flight.name, flight.truth, samples, calibration.channel_names,
                          flight.inputs.start_stamp_s)


def screened_in_folds(flights: Sequence[LabelledFlight], folds: Sequence[Fold],
                      calibrate: Calibrate, false_alarm_probability: float,
                      calibration_flights: Sequence[LabelledFlight] | None = None,
                      margin_s: float = ONSET_MARGIN_S,
                      seen: Seen | None = None) -> list[FlightOutcome]:
    """Every flight screened with calibrate(the fault-free parts of its fold's calibration
    flights: indices into calibration_flights, flights themselves by default), in the order
    of flights; seen told of each."""
    calibration_flights = flights if calibration_flights is None else calibration_flights
    parts = [fault_free_part(flight, margin_s) for flight in calibration_flights]
    return in_folds(
        len(flights), folds,
        lambda indices: calibrate([parts[j] for j in indices if parts[j] is not None]),
        lambda k, calibration: screened(flights[k], calibration, false_alarm_probability,
                                        seen))


def in_folds(count: int, folds: Sequence[Fold],
             calibrated: Callable[[list[int]], Any],
             outcome: Callable[[int, Any], FlightOutcome]) -> list[FlightOutcome]:
    """Any detector's outcomes over folds: per fold, calibrated(its calibration indices) once,
    then outcome(k, that calibration) of each flight k it screens; in the order 0..count-1."""
    outcomes: dict[int, FlightOutcome] = {}
    for screened_indices, calibration_indices in folds:
        calibration = calibrated(calibration_indices)
        for k in screened_indices:
            outcomes[k] = outcome(k, calibration)
    return [outcomes[k] for k in range(count)]
