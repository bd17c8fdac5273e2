#!/usr/bin/env python3
"""ALFA's failure kinds seeded in simulation, and how soon the detector finds each (a study).

    python -m studies.alfa_kinds --vehicle VEHICLE [--flights 20] [--first-seed 501]
        [--calibration FILE] [--json FILE]

For each of ALFA's kinds (both ailerons, one aileron, the elevator and the rudder stuck at
0, as ALFA's injection pins them, and the engine cut), flies --flights variants of the
vehicle's fault-free scenario (seeds from --first-seed, winds of 20-25 % of its airspeed in
as many directions; seeds the calibrations never flew: 501, the default, chose the fast
test's settings, 901 judges them) with the failure from an onset drawn in
60-120 s (seeded), to 30 s after it; and --flights fault-free flights as long (the longest
onset plus 30 s). The detector runs offline on each (detector_node's defaults, the vehicle's
shipped calibration or --calibration's, on its 0.2 s grid) and counts, per kind: the flights
with a combined alarm within 5 s of the onset (ALFA's evaluator counts a later one as a
miss), the median and largest delay of those found at all, and the flights with a combined
alarm before the onset (after the detector's settling); and the fault-free flights with any
alarm. The detector sees what ALFA's logs show: the pinned
surface position or throttle is among its inputs, as measured.

Beside each failed flight it flies its twin: the same seed, wind and turbulence without the
failure, so that the two differ by what the failure did and nothing else. On the
calibration's generators, with their fault-free parameters (theta0), the twins' residual
difference over the WITHIN_S after the onset, each generator's in units of its residual's
fault-free spread (the twin's, after settling), gives the matched filter's signal-to-noise
ratio: what a detector told the onset and the failure's exact signature would see, white
noise assumed. Below REQUIRED_SNR even that detector, allowed a 5 % false-alarm rate on
its one test, finds the failure in fewer than 90 % of flights: the count of flights above
it bounds what any detector on these residuals can find within WITHIN_S.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path
from statistics import NormalDist

import numpy as np
from uav_aircraft.vehicles import vehicle_names
from uav_common.channels import ACTUATOR_FAULT_NAMES
from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.chain.offline import GridFlight, fault_free_flights, fly_on_grid_each
from uav_fault_estimator.detection.calibration import (
    DEFAULT_SAMPLE_PERIOD_S,
    Calibration,
)
from uav_fault_estimator.detection.detector import RegressionFeed, flight_samples, run_detector
from uav_fault_estimator.detection.detector_settings import (
    DetectorSettings,
    detector_calibration,
)
from uav_sim.scenario import ACTUATOR_FAULT_PCT, Scenario, SeededFault

# the default: other seeds than the calibrations' (101-112, 301-304) and the studies'
FIRST_SEED = 501
ONSET_RANGE_S = (60.0, 120.0)
AFTER_ONSET_S = 30.0
WITHIN_S = 5.0  # ALFA's evaluator: a detection later than this is a miss
FAULT_FREE = "fault_free"
# The kind an alarm should name for each failure (generators.FAILURE_GENERATORS' kinds).
NAMED_AS = {"aileron_stuck": "aileron", "left_aileron_stuck": "aileron",
            "right_aileron_stuck": "aileron", "elevator_stuck": "elevator",
            "rudder_stuck": "rudder", "engine_cut": "engine"}
# The matched filter's signal-to-noise ratio for 90 % detection at a 5 % false-alarm rate.
REQUIRED_SNR = NormalDist().inv_cdf(0.95) + NormalDist().inv_cdf(0.90)


def flights(vehicle: str, count: int, first_seed: int = FIRST_SEED
            ) -> list[tuple[str, float, Scenario]]:
    """(kind or FAULT_FREE, onset [s] or nan, scenario) of every flight of the study, seeds
    from first_seed; the failed flights' twins are twin(scenario)."""
    rng = np.random.default_rng(first_seed)
    table = []
    for k, kind in enumerate((*ACTUATOR_FAULT_NAMES, FAULT_FREE)):
        bases = fault_free_flights(count, first_seed + count * k, 15.0 * k, vehicle)
        for base in bases:
            onset_s = float(rng.uniform(*ONSET_RANGE_S))
            if kind == FAULT_FREE:
                table.append((kind, float("nan"), dataclasses.replace(
                    base, duration_s=ONSET_RANGE_S[1] + AFTER_ONSET_S)))
                continue
            fault = SeededFault(kind, onset_s, 0.0, ACTUATOR_FAULT_PCT)
            table.append((kind, onset_s, dataclasses.replace(
                base, duration_s=onset_s + AFTER_ONSET_S, faults=(fault,))))
    return table


def twin(scenario: Scenario) -> Scenario:
    """The scenario without its seeded faults: the same seed, wind, turbulence and length."""
    return dataclasses.replace(scenario, faults=())


def generator_residuals(flight: GridFlight, calibration: Calibration
                        ) -> tuple[np.ndarray, np.ndarray]:
    """times (K,) [s] of the samples every generator of the calibration can use, and
    their residuals y - phiᵀ theta0 (K, G), generators in the calibration's order."""
    feed = RegressionFeed(calibration.channel_names, calibration.sample_period_s)
    times_s, rows = [], []
    for time_s, state, controls, _, setpoints in flight_samples(flight.detector_flight):
        regression = feed.step(time_s, state, controls, setpoints)
        if regression is not None:
            times_s.append(time_s)
            rows.append([y - phi @ calibration.channels[name].theta0
                         for name, (phi, y) in regression.items()])
    return np.array(times_s), np.array(rows)


def signal_to_noise(failed: GridFlight, twin_flight: GridFlight, calibration: Calibration,
                    onset_s: float) -> float:
    """The matched filter's signal-to-noise ratio of the failure over (onset, onset +
    WITHIN_S]: sqrt(sum over samples and generators of (residual difference / fault-free
    spread)^2), the spread the twin's residual's standard deviation after settling."""
    times_s, failed_residuals = generator_residuals(failed, calibration)
    twin_times_s, twin_residuals = generator_residuals(twin_flight, calibration)
    common_s, mine, theirs = np.intersect1d(times_s, twin_times_s, return_indices=True)
    spread = np.std(twin_residuals[twin_times_s >= calibration.settle_s], axis=0)
    window = (common_s > onset_s) & (common_s <= onset_s + WITHIN_S)
    difference = failed_residuals[mine[window]] - twin_residuals[theirs[window]]
    return float(np.sqrt(np.sum((difference / spread) ** 2)))


def first_alarms(flight: GridFlight, calibration: Calibration, false_alarm_probability: float,
                 onset_s: float) -> tuple[float | None, bool, str]:
    """The first combined alarm's delay after the onset [s] (None: none), whether one came
    before it (any alarm at all on a fault-free flight, onset nan), and the kind the first
    one after the onset names (empty: none)."""
    alarms = [(sample.time_s, sample.cause) for sample in run_detector(
        calibration, flight.detector_flight, false_alarm_probability)
        if sample.combined_alarm]
    if np.isnan(onset_s):
        return None, bool(alarms), ""
    after = [(t - onset_s, cause) for t, cause in alarms if t >= onset_s]
    return ((float(after[0][0]) if after else None), any(t < onset_s for t, _ in alarms),
            after[0][1] if after else "")


def summary(rows: list[tuple[str, float, float | None, bool, str, float]]) -> dict:
    """Per kind: found within WITHIN_S, found at all, delays, false alarms before onset, the
    found flights whose first alarm names the kind's failed part (NAMED_AS), and the flights
    whose signal-to-noise ratio reaches REQUIRED_SNR (rows: kind, onset, delay, early alarm,
    named kind, signal-to-noise ratio)."""
    result = {}
    for kind in (*ACTUATOR_FAULT_NAMES, FAULT_FREE):
        mine = [row for row in rows if row[0] == kind]
        delays = [row[2] for row in mine if row[2] is not None]
        ratios = [row[5] for row in mine]
        result[kind] = {
            "flights": len(mine),
            "false_alarm_flights": int(sum(row[3] for row in mine)),
            **({} if kind == FAULT_FREE else {
                "found_within_5_s": int(sum(d <= WITHIN_S for d in delays)),
                "found": len(delays),
                "named_right": int(sum(row[2] is not None and row[4] == NAMED_AS[kind]
                                       for row in mine)),
                "median_delay_s": float(np.median(delays)) if delays else None,
                "largest_delay_s": float(max(delays)) if delays else None,
                "detectable_within_5_s": int(sum(r >= REQUIRED_SNR for r in ratios)),
                "median_signal_to_noise": float(np.median(ratios))})}
    return result


def print_table(result: dict) -> None:
    print(f"{'kind':<20}{'within 5 s':>11}{'found':>7}{'named':>7}{'median s':>10}"
          f"{'largest s':>10}{'early alarms':>14}{'detectable':>12}{'median SNR':>12}")
    for kind, entry in result.items():
        if kind == FAULT_FREE:
            print(f"{'fault-free':<20}{'':>11}{'':>7}{'':>7}{'':>10}{'':>10}"
                  f"{entry['false_alarm_flights']:>9} of {entry['flights']}")
            continue
        median = "-" if entry["median_delay_s"] is None else f"{entry['median_delay_s']:.1f}"
        largest = "-" if entry["largest_delay_s"] is None else f"{entry['largest_delay_s']:.1f}"
        print(f"{kind:<20}{entry['found_within_5_s']:>6} of {entry['flights']:<2}"
              f"{entry['found']:>5}{entry['named_right']:>7}{median:>10}{largest:>10}"
              f"{entry['false_alarm_flights']:>14}"
              f"{entry['detectable_within_5_s']:>12}{entry['median_signal_to_noise']:>12.1f}")


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicle", choices=vehicle_names(), required=True)
    parser.add_argument("--flights", type=int, default=20)
    parser.add_argument("--first-seed", type=int, default=FIRST_SEED)
    parser.add_argument("--calibration", type=Path, help="default: the vehicle's shipped one")
    parser.add_argument("--json", type=Path)
    add_campaign_arguments(parser)
    arguments = parser.parse_args()
    started = time.monotonic()
    table = flights(arguments.vehicle, arguments.flights, arguments.first_seed)
    twins = [twin(scenario) for kind, _, scenario in table if kind != FAULT_FREE]
    with Campaign(campaign_options(arguments)) as campaign:
        grid = fly_on_grid_each(campaign, [scenario for *_, scenario in table] + twins,
                                DEFAULT_SAMPLE_PERIOD_S)
    grid, twin_grid = grid[:len(table)], iter(grid[len(table):])
    settings = DetectorSettings(vehicle=arguments.vehicle,
                                calibration_file=str(arguments.calibration or ""))
    calibration = detector_calibration(settings)
    rows = [(kind, onset_s, *first_alarms(flight, calibration,
                                          settings.false_alarm_probability, onset_s),
             math.nan if kind == FAULT_FREE else signal_to_noise(
                 flight, next(twin_grid), calibration, onset_s))
            for (kind, onset_s, _), flight in zip(table, grid, strict=True)]
    result = summary(rows)
    print_table(result)
    wall_s = time.monotonic() - started
    print(f"{len(table)} flights in {wall_s:.0f} s")
    if arguments.json:
        arguments.json.write_text(json.dumps(
            {"vehicle": arguments.vehicle, "flights_per_kind": arguments.flights,
             "first_seed": arguments.first_seed,
             "generators": list(calibration.channels),
             "within_s": WITHIN_S, "required_signal_to_noise": REQUIRED_SNR,
             "kinds": result, "wall_s": wall_s}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
