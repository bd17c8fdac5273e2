#!/usr/bin/env python3
"""Learn which failure a detector alarm resembles, from simulated failures.

    python scripts/learn_signatures.py [--vehicle aerosonde] [--flights 20]
        [--first-seed 501] [--calibration FILE] [--neighbours 5] [--out FILE]

Flies every failure kind of chain.failure_flights (ALFA's failures, the seven model faults
as steps and ramps) on --flights of the vehicle's fault-free flights (seeds from
--first-seed: not the calibrations' 101-112, and not the seeds that judge the signatures,
from 901 in studies/failure_kinds.py), runs the detector on each (the vehicle's shipped
calibration or --calibration's, detector_node's defaults) and keeps, at its first combined
alarm after the onset, its signature (each channel's fast-test change, then its parameters'
deviations) with the part that failed (signatures.CAUSE_OF_FAULT): the signatures
detector_node names an alarm's cause by, by its --neighbours nearest. Writes them (default:
the vehicle folder's failure_signatures.yaml in this source tree); they hold for the
calibration's channels and spreads only.
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
from uav_fault_estimator.chain.failure_flights import FAULT_FREE, failure_flights
from uav_fault_estimator.chain.offline import fly_on_grid_each
from uav_fault_estimator.detection.calibration import DEFAULT_SAMPLE_PERIOD_S, Calibration
from uav_fault_estimator.detection.detector import (
    DetectorSample,
    first_combined_alarm,
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


def examples(vehicle: str, count: int, first_seed: int, calibration: Calibration,
             false_alarm_probability: float, arguments: argparse.Namespace
             ) -> tuple[list[tuple[str, np.ndarray]], int]:
    """(cause, signature at the first alarm) of every failed flight the detector found, and
    how many failed flights were flown."""
    table = [flight for flight in failure_flights(vehicle, count, first_seed)
             if flight.kind != FAULT_FREE]
    with Campaign(campaign_options(arguments)) as campaign:
        grid = fly_on_grid_each(campaign, [flight.scenario for flight in table],
                                DEFAULT_SAMPLE_PERIOD_S)
    found = []
    for flight, flown in zip(table, grid, strict=True):
        signature = first_alarm_signature(run_detector(
            calibration, flown.detector_flight, false_alarm_probability), flight.onset_s)
        if signature is not None:
            found.append((CAUSE_OF_FAULT[flight.scenario.faults[0].name], signature))
    return found, len(table)


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
    try:
        calibration = detector_calibration(settings)
        found, flown = examples(arguments.vehicle, arguments.flights, arguments.first_seed,
                                calibration, settings.false_alarm_probability, arguments)
        learned_from = (f"{len(found)} of {flown} simulated failures of {arguments.vehicle} "
                        f"(seeds from {arguments.first_seed}) the detector found")
        signatures = learned_signatures(signature_features(calibration), found,
                                        arguments.neighbours, learned_from)
    except ValueError as error:
        print(f"learn_signatures.py: {error}", file=sys.stderr)
        return 1
    header = ("# Written by scripts/learn_signatures.py: each signature (the fast-test changes "
              "and\n# the parameters' deviations) at a simulated failure's first alarm, as a "
              "unit direction.\n")
    write_calibration(out, header, signatures_to_dict(signatures), f"{flown} flights",
                      time.monotonic() - started)
    return 0


if __name__ == "__main__":
    sys.exit(main())
