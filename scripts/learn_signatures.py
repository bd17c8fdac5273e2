#!/usr/bin/env python3
"""Learn which failure a detector alarm resembles, and each failure's shape, from simulated
failures.

    python scripts/learn_signatures.py [--vehicle aerosonde] [--flights 20]
        [--first-seed 501] [--calibration FILE] [--neighbours 5] [--out FILE]

Flies every failure kind of chain.failure_flights (ALFA's failures, the seven model faults
as steps and ramps) on --flights of the vehicle's fault-free flights, and those fault-free
flights (the failures' twins), with seeds from --first-seed (not the calibrations' 101-112,
and not the seeds that judge what is learned here, from 901 in studies/failure_kinds.py),
and the detector's calibration flights. With the vehicle's shipped calibration or
--calibration's, it learns:

- the template test's templates (detection.templates.learn_templates): the calibration
  flights' residuals with the parameters fixed give the whitening filters and each
  template's fault-free distribution; each kind's shape is the mean of its flights' whitened
  difference from their twins over the 5 s after the reference (ALFA's limit for a
  detection), kept where it finds its kind within that time and keeps the calibration
  flights quiet;
- then, running the detector with those templates (detector_node's defaults), at each
  failed flight's first combined alarm after the onset its signature (each channel's
  fast-test change, then its parameters' deviations) with the part that failed
  (signatures.CAUSE_OF_FAULT): the signatures detector_node names an alarm's cause by, by its
  --neighbours nearest.

Writes both (default: the vehicle folder's failure_signatures.yaml in this source tree);
they hold for the calibration's channels and spreads only.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from uav_aircraft.paths import calibration_output_path
from uav_aircraft.vehicles import DEFAULT_VEHICLE, FAILURE_SIGNATURES_FILE, vehicle_names
from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.chain.failure_flights import FAULT_FREE, FailureFlight, failure_flights
from uav_fault_estimator.chain.offline import (
    CALIBRATION_FIRST_SEED,
    CALIBRATION_FLIGHTS,
    GridFlight,
    fault_free_flights,
    fly_on_grid_each,
)
from uav_fault_estimator.detection.calibration import DEFAULT_SAMPLE_PERIOD_S, Calibration
from uav_fault_estimator.detection.detector import (
    DetectorSample,
    first_combined_alarm,
    fixed_residuals,
    run_detector,
)
from uav_fault_estimator.detection.detector_settings import (
    DetectorSettings,
    detector_calibration,
)
from uav_fault_estimator.detection.signatures import (
    CAUSE_OF_FAULT,
    DEFAULT_NEIGHBOURS,
    learned_signatures,
    signature_features,
    signatures_to_dict,
)
from uav_fault_estimator.detection.templates import (
    TEMPLATES_KEY,
    FailureTemplates,
    LearningFlight,
    learn_templates,
    templates_to_dict,
    whitened,
    whitening_filters,
)
from uav_fault_estimator.flight_logs.evaluation import ALFA_DETECTION_LIMIT_S
from uav_fault_estimator.reporting.calibration_output import write_calibration

FIRST_SEED = 501


def first_alarm_signature(samples: list[DetectorSample], onset_s: float
                          ) -> np.ndarray | None:
    """The signature at the first combined alarm at or after onset_s [s] (None: no alarm,
    or its signature not yet known)."""
    first = first_combined_alarm(samples, onset_s)
    if first is None or not np.all(np.isfinite(first.signature)):
        return None
    return first.signature


def cause_of(flight: FailureFlight) -> str:
    """The part a failed flight's fault is a failure of (signatures.CAUSE_OF_FAULT)."""
    return CAUSE_OF_FAULT[flight.scenario.faults[0].name]


def templates(table: list[FailureFlight], grid: list[GridFlight], fault_free: list[GridFlight],
              settings: DetectorSettings, calibration: Calibration, learned_from: str
              ) -> FailureTemplates | None:
    """The template test's templates (templates.learn_templates) from the failed flights
    of table and their twins (grid: each one flown) and the calibration flights
    (fault_free), on the calibration's residuals with its parameters fixed."""
    def residuals(flown: GridFlight) -> tuple[np.ndarray, np.ndarray]:
        return fixed_residuals(run_detector(calibration, flown.detector_flight,
                                            settings.false_alarm_probability))

    quiet = [residuals(flown) for flown in fault_free]
    filters = whitening_filters([r[t >= calibration.settle_s] for t, r in quiet])
    flown = [(flight, residuals(one)) for flight, one in zip(table, grid, strict=True)]
    twins = {flight.twin: whitened(r, filters)
             for flight, (_, r) in flown if flight.kind == FAULT_FREE}
    length = round(ALFA_DETECTION_LIMIT_S / calibration.sample_period_s)
    examples = []
    for flight, (times_s, r) in flown:
        after = int(np.searchsorted(times_s, flight.reference_s, side="right"))
        twin = twins.get(flight.twin)
        if flight.kind == FAULT_FREE or after + length > min(len(r), len(twin)):
            continue  # a failed flight that ends within the shape: nothing to learn from
        white = whitened(r, filters)
        examples.append(LearningFlight(
            flight.kind, cause_of(flight), white,
            white[after:after + length] - twin[after:after + length],
            (times_s > flight.onset_s)
            & (times_s <= flight.reference_s + ALFA_DETECTION_LIMIT_S)))
    return learn_templates(
        filters, calibration.fast_reference,
        [whitened(r, filters)[t >= calibration.settle_s] for t, r in quiet], examples,
        settings.template_false_alarms_per_hour, calibration.sample_period_s, learned_from)


def signatures(table: list[FailureFlight], grid: list[GridFlight], settings: DetectorSettings,
               calibration: Calibration, shapes: FailureTemplates | None
               ) -> list[tuple[str, np.ndarray]]:
    """(cause, signature at the first alarm) of every failed flight the detector (with the
    templates) found."""
    found = []
    for flight, flown in zip(table, grid, strict=True):
        if flight.kind == FAULT_FREE:
            continue
        signature = first_alarm_signature(run_detector(
            calibration, flown.detector_flight, settings.false_alarm_probability,
            settings.fast_false_alarms_per_hour, templates=shapes,
            template_false_alarms_per_hour=settings.template_false_alarms_per_hour),
            flight.onset_s)
        if signature is not None:
            found.append((cause_of(flight), signature))
    return found


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicle", choices=vehicle_names(), default=DEFAULT_VEHICLE)
    parser.add_argument("--flights", type=int, default=20)
    parser.add_argument("--first-seed", type=int, default=FIRST_SEED)
    parser.add_argument("--calibration", type=Path, help="default: the vehicle's shipped one")
    parser.add_argument("--neighbours", type=int, default=DEFAULT_NEIGHBOURS)
    parser.add_argument("--out", type=Path,
                        help="default: the vehicle's folder in this source tree")
    add_campaign_arguments(parser)
    arguments = parser.parse_args()
    out = arguments.out or calibration_output_path(arguments.vehicle, FAILURE_SIGNATURES_FILE)
    started = time.monotonic()
    settings = DetectorSettings(vehicle=arguments.vehicle,
                                calibration_file=str(arguments.calibration or ""))
    table = failure_flights(arguments.vehicle, arguments.flights, arguments.first_seed)
    quiet = fault_free_flights(CALIBRATION_FLIGHTS, CALIBRATION_FIRST_SEED,
                               vehicle=arguments.vehicle)
    with Campaign(campaign_options(arguments)) as campaign:
        grid = fly_on_grid_each(campaign, [flight.scenario for flight in table] + quiet,
                                DEFAULT_SAMPLE_PERIOD_S)
    grid, fault_free = grid[:len(table)], grid[len(table):]
    failed = sum(flight.kind != FAULT_FREE for flight in table)
    seeds = f"{arguments.vehicle} (seeds from {arguments.first_seed})"
    try:
        calibration = detector_calibration(settings)
        shapes = templates(table, grid, fault_free, settings, calibration,
                           f"{failed} simulated failures of {seeds} and their fault-free "
                           f"twins; {len(quiet)} calibration flights (seeds from "
                           f"{CALIBRATION_FIRST_SEED})")
        found = signatures(table, grid, settings, calibration, shapes)
        learned = learned_signatures(
            signature_features(calibration), found, arguments.neighbours,
            f"{len(found)} of {failed} simulated failures of {seeds} the detector found")
    except ValueError as error:
        print(f"learn_signatures.py: {error}", file=sys.stderr)
        return 1
    header = ("# Written by scripts/learn_signatures.py: each signature (the fast-test changes "
              "and\n# the parameters' deviations) at a simulated failure's first alarm, as a "
              "unit direction;\n# the template test's whitening and its failures' shapes.\n")
    content = signatures_to_dict(learned)
    if shapes is not None:
        content[TEMPLATES_KEY] = templates_to_dict(shapes)
    write_calibration(out, header, content, f"{len(table) + len(quiet)} flights",
                      time.monotonic() - started)
    return 0


if __name__ == "__main__":
    sys.exit(main())
