#!/usr/bin/env python3
"""Every failure kind and model fault seeded in simulation: what the signals carry and how
soon the detector finds each (a study).

    python -m studies.failure_kinds --vehicle VEHICLE [--flights 20] [--first-seed 501]
        [--kinds KIND ...] [--calibration FILE] [--signatures FILE] [--json FILE]

The flights: chain.failure_flights (ALFA's failures, the seven model faults as steps and
ramps, each kind on --flights of the vehicle's fault-free flights, which are flown too;
seeds from --first-seed: seeds the calibrations never flew; 501, the default, chose the
fast test's settings and learned the shipped signatures and templates, 901 judges them).
The detector runs offline on each (detector_node's defaults, the vehicle's shipped
calibration and signatures, with the templates the signatures file holds, or the files
given, on its 0.2 s grid) and counts, per kind: the flights with a combined alarm within
WITHIN_S of the reference (the onset; a ramp's reaching 2 %: ALFA's evaluator counts a later
one as a miss), the median and largest delay of those found at all, the found flights whose
first alarm names the failed part (signatures.CAUSE_OF_FAULT), and the flights with a
combined alarm before the onset (after the detector's settling); and the fault-free flights
with any alarm. The detector sees what ALFA's logs show: the pinned
surface position or throttle is among its inputs, as measured.

The bound: each failed flight's twin is its fault-free flight, the same seed, wind and
turbulence without the fault, so that the two differ by what the fault did and nothing
else. On the calibration's generators, with their fault-free parameters (theta0), the
twins' residual difference after the reference, each generator's in units of its
residual's fault-free spread (the twin's, after settling), gives the matched filter's
signal-to-noise ratio: what a detector told the onset and the fault's exact signature would
see, white noise assumed. Below REQUIRED_SNR even that detector, allowed a 5 % false-alarm
rate on its one test, finds the fault in fewer than 90 % of flights: the flights at or above
it over WITHIN_S are "detectable", and the bound's delay is the time after the reference at
which the ratio first reaches it.

The sliding bound asks the same matched filter what a detector must do: it is told the
fault's signature (the twins' residual difference over the WITHIN_S after the reference) but
not its onset, so it slides over every flight, each generator's residual taken from its mean
over the fast test's reference before the window, as the fast test takes it; its threshold
is the largest value it reaches on any of the fault-free flights after settling (so that none
alarms, as the targets ask). It runs twice: on the residuals as they are, and on them
whitened by an autoregressive model (templates.WHITENING_ORDER) of the fault-free flights' own, each
run with its own threshold; a detectable flight either finds at the end of WITHIN_S is
"found by the sliding bound". For Gaussian residuals of that colour no test finds a known
signal more often at the same false-alarm level (Neyman-Pearson); a detector, which is not
told the signature, finds no more unless the residuals' tails hold what these filters miss.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from statistics import NormalDist
from typing import NamedTuple

import numpy as np
from uav_aircraft.vehicles import vehicle_names
from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.chain.failure_flights import (
    FAULT_FREE,
    RAMP_S,
    FailureFlight,
    failure_flights,
    model_fault_magnitudes_pct,
)
from uav_fault_estimator.chain.offline import GridFlight, fly_on_grid_each
from uav_fault_estimator.detection.calibration import (
    DEFAULT_SAMPLE_PERIOD_S,
)
from uav_fault_estimator.detection.detector import (
    DetectorSample,
    SelfTuningDetector,
    detector_samples,
    first_combined_alarm,
    fixed_residuals,
)
from uav_fault_estimator.detection.detector_settings import (
    DetectorSettings,
    self_tuning_detector,
)
from uav_fault_estimator.detection.signatures import CAUSE_OF_FAULT
from uav_fault_estimator.detection.templates import (
    matched_filter,
    whitened,
    whitening_filters,
)
from uav_fault_estimator.flight_logs.evaluation import ALFA_DETECTION_LIMIT_S as WITHIN_S

FIRST_SEED = 501  # other seeds than the calibrations' (101-112, 301-304) and the studies'
# The matched filter's signal-to-noise ratio for 90 % detection at a 5 % false-alarm rate.
REQUIRED_SNR = NormalDist().inv_cdf(0.95) + NormalDist().inv_cdf(0.90)


Residuals = tuple[np.ndarray, np.ndarray]  # fixed_residuals' times [s] and residuals


def cumulative_signal_to_noise(failed: Residuals, twin: Residuals, settle_s: float,
                               reference_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The matched filter's signal-to-noise ratio over (reference, t] for each sample time t
    after the reference both flights have: sqrt(sum over samples and generators of
    (residual difference / fault-free spread)^2), the spread the twin's residual's standard
    deviation after settle_s. Returns (t - reference [s], ratio)."""
    (times_s, failed_residuals), (twin_times_s, twin_residuals) = failed, twin
    common_s, mine, theirs = np.intersect1d(times_s, twin_times_s, return_indices=True)
    spread = np.std(twin_residuals[twin_times_s >= settle_s], axis=0)
    after = common_s > reference_s
    difference = failed_residuals[mine[after]] - twin_residuals[theirs[after]]
    ratio = np.sqrt(np.cumsum(np.sum((difference / spread) ** 2, axis=1)))
    return common_s[after] - reference_s, ratio


def bound(failed: Residuals, twin: Residuals, settle_s: float, reference_s: float
          ) -> tuple[float, float | None]:
    """The signal-to-noise ratio over (reference, reference + WITHIN_S] (0 when no sample
    lies there), and the time after the reference [s] at which it first reaches REQUIRED_SNR
    (None: not within the flight)."""
    delays_s, ratio = cumulative_signal_to_noise(failed, twin, settle_s, reference_s)
    within = delays_s <= WITHIN_S
    reached = np.flatnonzero(ratio >= REQUIRED_SNR)
    return (float(ratio[within][-1]) if within.any() else 0.0,
            float(delays_s[reached[0]]) if reached.size else None)


def found_by_sliding_bound(failed: Residuals, twin: Residuals, fault_free: list[Residuals],
                           settle_s: float, reference_s: float, reference: int) -> bool:
    """Whether the matched filter told the twins' difference over (reference_s, reference_s
    + WITHIN_S] (its signature), slid along the failed flight, exceeds at that interval's
    last sample the largest value it reaches on the fault-free flights after settle_s;
    reference: the samples whose mean each window is taken from."""
    (times_s, failed_residuals), (twin_times_s, twin_residuals) = failed, twin
    common_s, mine, theirs = np.intersect1d(times_s, twin_times_s, return_indices=True)
    within = (common_s > reference_s) & (common_s <= reference_s + WITHIN_S)
    if not within.any():
        return False
    signature = failed_residuals[mine[within]] - twin_residuals[theirs[within]]
    spread = np.std(twin_residuals[twin_times_s >= settle_s], axis=0)
    threshold = max(np.nanmax(np.where(
        flight_times_s >= settle_s,
        matched_filter(signature, spread, flight_residuals, reference), np.nan))
        for flight_times_s, flight_residuals in fault_free)
    return bool(matched_filter(signature, spread, failed_residuals, reference)[mine[within][-1]]
                > threshold)


class FlightResult(NamedTuple):
    """What one flight showed: its kind, the first combined alarm's delay after the
    reference [s] (None: none), an alarm before the onset (on a fault-free flight: any),
    whether the first alarm after the onset names the failed part
    (signatures.CAUSE_OF_FAULT), the bound's signal-to-noise ratio within WITHIN_S and its
    delay [s] (nan and None for a fault-free flight), and whether the sliding bound finds
    it (a detectable flight only)."""

    kind: str
    delay_s: float | None
    early_alarm: bool
    named_right: bool
    signal_to_noise: float
    bound_delay_s: float | None
    sliding_bound_found: bool = False


def detector_result(flight: FailureFlight, samples: list[DetectorSample]
                    ) -> tuple[float | None, bool, bool]:
    """From the detector's samples over the flight: the first combined alarm's delay after
    the reference [s] (None: none after the onset), whether one came before the onset (any
    alarm on a fault-free flight), and whether the first alarm after the onset names the
    failed part."""
    if flight.kind == FAULT_FREE:
        return None, first_combined_alarm(samples) is not None, False
    early = any(s.combined_alarm for s in samples if s.time_s < flight.onset_s)
    first = first_combined_alarm(samples, flight.onset_s)
    if first is None:
        return None, early, False
    (fault,) = flight.scenario.faults
    return (float(first.time_s - flight.reference_s), early,
            first.cause == CAUSE_OF_FAULT[fault.name])


def judge(table: list[FailureFlight], grid: list[GridFlight], detector: SelfTuningDetector
          ) -> list[FlightResult]:
    """Each flight's FlightResult, from one run of the detector over each flight."""
    calibration = detector.calibration
    runs = [detector_samples(detector, flown.detector_flight) for flown in grid]
    twins = {flight.twin: fixed_residuals(samples)
             for flight, samples in zip(table, runs, strict=True) if flight.kind == FAULT_FREE}
    # the sliding bound's two views of the residuals, each with its fault-free flights
    # (whitened once): as they are, and whitened; each keeps its own threshold above every
    # fault-free flight, so that together they keep those flights quiet too
    filters = whitening_filters([residuals[times_s >= calibration.settle_s]
                                 for times_s, residuals in twins.values()])

    def whitened_view(flight: Residuals) -> Residuals:
        return flight[0], whitened(flight[1], filters)

    views = [(lambda flight: flight, twins),
             (whitened_view, {twin: whitened_view(residuals)
                              for twin, residuals in twins.items()})]
    results = []
    for flight, samples in zip(table, runs, strict=True):
        detector = detector_result(flight, samples)
        if flight.kind == FAULT_FREE:
            results.append(FlightResult(flight.kind, *detector, np.nan, None))
            continue
        failed = fixed_residuals(samples)
        ratio, bound_delay_s = bound(failed, twins[flight.twin], calibration.settle_s,
                                     flight.reference_s)
        sliding = ratio >= REQUIRED_SNR and any(
            found_by_sliding_bound(view(failed), fault_free[flight.twin],
                                   list(fault_free.values()), calibration.settle_s,
                                   flight.reference_s, calibration.fast_reference)
            for view, fault_free in views)
        results.append(FlightResult(flight.kind, *detector, ratio, bound_delay_s, sliding))
    return results


def median(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def summary(results: list[FlightResult]) -> dict:
    """Per kind (the order they come in): the flights with an alarm before the onset; for a
    fault, the flights found within WITHIN_S and at all, those the bound calls detectable
    and of them those found within WITHIN_S and those the sliding bound finds, the
    detector's and the bound's median delays
    [s], the detector's largest, the found flights whose first alarm names the failed part
    and the median signal-to-noise ratio."""
    found: dict[str, dict] = {}
    for kind in dict.fromkeys(result.kind for result in results):
        mine = [result for result in results if result.kind == kind]
        entry = {"flights": len(mine),
                 "false_alarm_flights": int(sum(result.early_alarm for result in mine))}
        if kind != FAULT_FREE:
            delays = [result.delay_s for result in mine if result.delay_s is not None]
            detectable = [result for result in mine if result.signal_to_noise >= REQUIRED_SNR]
            entry |= {
                "found_within_5_s": int(sum(d <= WITHIN_S for d in delays)),
                "found": len(delays),
                "detectable_within_5_s": len(detectable),
                "detectable_found_within_5_s": int(sum(
                    result.delay_s is not None and result.delay_s <= WITHIN_S
                    for result in detectable)),
                "sliding_bound_found": int(sum(r.sliding_bound_found for r in detectable)),
                "median_delay_s": median(delays),
                "largest_delay_s": max(delays) if delays else None,
                "bound_found": int(sum(r.bound_delay_s is not None for r in mine)),
                "median_bound_delay_s": median([r.bound_delay_s for r in mine
                                                if r.bound_delay_s is not None]),
                "named_right": int(sum(result.named_right for result in mine)),
                "median_signal_to_noise": float(np.median([r.signal_to_noise for r in mine]))}
        found[kind] = entry
    return found


def figure(value: float | None, digits: int = 1) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def print_table(result: dict) -> None:
    print(f"{'kind':<36}{'detectable':>11}{'found 5 s':>10}{'of them':>8}{'sliding':>8}"
          f"{'found':>6}"
          f"{'named':>6}{'median s':>9}{'bound s':>8}{'largest s':>10}{'early':>6}"
          f"{'SNR':>7}")
    for kind, entry in result.items():
        if kind == FAULT_FREE:
            print(f"{'fault-free':<36}{'':>58}{'':>10}"
                  f"{entry['false_alarm_flights']:>3} of {entry['flights']}")
            continue
        print(f"{kind:<36}{entry['detectable_within_5_s']:>5} of {entry['flights']:<3}"
              f"{entry['found_within_5_s']:>10}{entry['detectable_found_within_5_s']:>8}"
              f"{entry['sliding_bound_found']:>8}"
              f"{entry['found']:>6}{entry['named_right']:>6}{figure(entry['median_delay_s']):>9}"
              f"{figure(entry['median_bound_delay_s']):>8}"
              f"{figure(entry['largest_delay_s']):>10}{entry['false_alarm_flights']:>6}"
              f"{entry['median_signal_to_noise']:>7.1f}")


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicle", choices=vehicle_names(), required=True)
    parser.add_argument("--flights", type=int, default=20)
    parser.add_argument("--first-seed", type=int, default=FIRST_SEED)
    parser.add_argument("--kinds", nargs="+", help="default: every kind")
    parser.add_argument("--calibration", type=Path, help="default: the vehicle's shipped one")
    parser.add_argument("--signatures", type=Path, help="default: the vehicle's shipped ones "
                        "where they are over the calibration's channels")
    parser.add_argument("--json", type=Path)
    add_campaign_arguments(parser)
    arguments = parser.parse_args()
    started = time.monotonic()
    try:
        table = failure_flights(arguments.vehicle, arguments.flights, arguments.first_seed,
                                arguments.kinds and tuple(arguments.kinds))
    except ValueError as error:
        parser.error(str(error))
    with Campaign(campaign_options(arguments)) as campaign:
        grid = fly_on_grid_each(campaign, [flight.scenario for flight in table],
                                DEFAULT_SAMPLE_PERIOD_S)
    settings = DetectorSettings(vehicle=arguments.vehicle,
                                calibration_file=str(arguments.calibration or ""),
                                signatures_file=str(arguments.signatures or ""))
    detector = self_tuning_detector(settings)
    calibration, signatures = detector.calibration, detector.signatures
    result = summary(judge(table, grid, detector))
    print_table(result)
    wall_s = time.monotonic() - started
    print(f"{len(table)} flights in {wall_s:.0f} s")
    if arguments.json:
        arguments.json.write_text(json.dumps(
            {"vehicle": arguments.vehicle, "flights_per_kind": arguments.flights,
             "first_seed": arguments.first_seed, "generators": list(calibration.channels),
             "signatures": None if signatures is None else signatures.learned_from,
             "within_s": WITHIN_S, "required_signal_to_noise": REQUIRED_SNR,
             "ramp_s": RAMP_S, "magnitudes_pct": model_fault_magnitudes_pct(arguments.vehicle),
             "kinds": result, "wall_s": wall_s}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
