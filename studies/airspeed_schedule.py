#!/usr/bin/env python3
"""Does the detector need its airspeed schedule? Measured on simulated flights.

    python -m studies.airspeed_schedule [--per-airspeed 4] [--json FILE]

Calibrates the detector three times: from the fault-free flights at 25 m/s alone, as the
shipped calibration is made (one speed: no schedule possible); from the same and more at
21, 25 and 29 m/s (offline.fault_free_flights' seeds and winds, --per-airspeed flights
each) without a schedule (the parameters' fault-free mean and spread over every speed);
and from those with the schedule (the means affine in the filtered airspeed:
self_tuning.airspeed_schedule). Then, on fault-free
flights at airspeeds the calibration did not see (19, 23, 27 and 33 m/s: two inside its
range, two outside), each test's false-alarm rate per sample against the designed P_FA
(detector_node's default); and on the aileron_loss scenario (90 % loss at 150 s) flown at
23 and 27 m/s, the delay of the first combined alarm. Prints the tables; --json writes
them.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.chain.offline import fly_on_grid_each
from uav_fault_estimator.detection.calibration import DEFAULT_SAMPLE_PERIOD_S
from uav_fault_estimator.detection.detector import run_detector
from uav_fault_estimator.detection.detector_settings import DetectorSettings
from uav_fault_estimator.flight_logs.screening import first_combined_alarm_s
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import load_scenario

from studies.airspeed_study import (
    CALIBRATIONS,
    TESTS,
    at_airspeed,
    compared_calibrations,
    fault_free_at,
    rates_per_group,
)

CALIBRATION_AIRSPEEDS_MPS = (21.0, 25.0, 29.0)
TEST_AIRSPEEDS_MPS = (19.0, 23.0, 27.0, 33.0)
FAULT_AIRSPEEDS_MPS = (23.0, 27.0)
TEST_FLIGHTS_PER_AIRSPEED = 3
CALIBRATION_SEED, TEST_SEED = 301, 401


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-airspeed", type=int, default=4,
                        help="calibration flights per airspeed")
    parser.add_argument("--json", type=Path, help="write the figures here")
    add_campaign_arguments(parser)
    arguments = parser.parse_args()
    p_fa = DetectorSettings().false_alarm_probability
    started = time.monotonic()
    aileron = load_scenario(scenarios_dir() / "aileron_loss.yaml")
    fault_start_s = min(fault.start_s for fault in aileron.faults)
    scenarios = [*fault_free_at(CALIBRATION_AIRSPEEDS_MPS, arguments.per_airspeed,
                                CALIBRATION_SEED),
                 *fault_free_at(TEST_AIRSPEEDS_MPS, TEST_FLIGHTS_PER_AIRSPEED, TEST_SEED),
                 *(at_airspeed(aileron, airspeed) for airspeed in FAULT_AIRSPEEDS_MPS)]
    with Campaign(campaign_options(arguments)) as campaign:
        flights = [flight.detector_flight for flight
                   in fly_on_grid_each(campaign, scenarios, DEFAULT_SAMPLE_PERIOD_S)]
    count = len(CALIBRATION_AIRSPEEDS_MPS) * arguments.per_airspeed
    calibration_flights, rest = flights[:count], flights[count:]
    faults = len(FAULT_AIRSPEEDS_MPS)
    test_flights, fault_flights = rest[:-faults], rest[-faults:]
    results = {}
    made = compared_calibrations(calibration_flights, arguments.per_airspeed)
    for name, calibration in made.items():
        per_airspeed = {f"{airspeed:g}": row for airspeed, row in zip(
            TEST_AIRSPEEDS_MPS, rates_per_group(calibration, test_flights,
                                                TEST_FLIGHTS_PER_AIRSPEED, p_fa), strict=True)}
        delays = {}
        for airspeed, flight in zip(FAULT_AIRSPEEDS_MPS, fault_flights, strict=True):
            alarm_s = first_combined_alarm_s(run_detector(calibration, flight, p_fa),
                                             fault_start_s)
            delays[f"{airspeed:g}"] = None if alarm_s is None else alarm_s - fault_start_s
        results[name] = {
            "false_alarm_rates": per_airspeed, "aileron_loss_delay_s": delays,
            "roll_gain_std": float(calibration.channels["roll"].parameter_std[0])}
    report = {"designed_false_alarm_probability": p_fa,
              "calibration_airspeeds_mps": list(CALIBRATION_AIRSPEEDS_MPS),
              "calibration_flights_per_airspeed": arguments.per_airspeed,
              "test_flights_per_airspeed": TEST_FLIGHTS_PER_AIRSPEED,
              "wall_s": round(time.monotonic() - started, 1), **results}
    print_tables(report)
    if arguments.json:
        arguments.json.write_text(json.dumps(report, indent=2) + "\n")
    return 0


def print_tables(report: dict) -> None:
    print(f"false-alarm rate per sample (designed {report['designed_false_alarm_probability']:g}"
          f"), calibrated at {report['calibration_airspeeds_mps']} m/s")
    print(f"{'airspeed':>8}  {'calibration':<12} " + " ".join(f"{test:>12}" for test in TESTS))
    for airspeed in report["unscheduled"]["false_alarm_rates"]:
        for name in CALIBRATIONS:
            row = report[name]["false_alarm_rates"][airspeed]
            print(f"{airspeed:>8}  {name:<12} " + " ".join(f"{row[test]:12.4f}" for test in TESTS))
    for name in CALIBRATIONS:
        delays = ", ".join(f"{airspeed} m/s: {'none' if delay is None else f'{delay:.1f} s'}"
                           for airspeed, delay in report[name]["aileron_loss_delay_s"].items())
        print(f"{name}: aileron loss detected after {delays}; roll gain spread "
              f"{report[name]['roll_gain_std']:.3f}")
    print(f"wall time {report['wall_s']} s")


if __name__ == "__main__":
    sys.exit(main())
