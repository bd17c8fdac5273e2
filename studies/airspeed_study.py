"""The detector's airspeed schedule, measured on simulated flights: fault-free
flights at several airspeeds calibrate it, with and without the schedule; flights at
airspeeds the calibration did not see give each test's false-alarm rate, and a seeded
aileron loss its detection delay. Shared by studies/airspeed_schedule.py and
tests/studies/test_airspeed_study.py. No ROS here."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
from uav_fault_estimator.chain.offline import fault_free_flights
from uav_fault_estimator.detection.calibration import (
    Calibration,
)
from uav_fault_estimator.detection.calibration_fit import calibrate
from uav_fault_estimator.detection.detector import DetectorFlight, run_detector
from uav_fault_estimator.detection.generators import SURFACE_GENERATORS
from uav_sim.scenario import Scenario

# The tests whose rates are measured, in the order of rates()' values.
TESTS = (*(f"glrt_{name}" for name in SURFACE_GENERATORS), "parameters", "combined")
CALIBRATIONS = ("one_airspeed", "unscheduled", "scheduled")  # compared_calibrations' keys


def at_airspeed(scenario: Scenario, airspeed_mps: float) -> Scenario:
    """The scenario flown at another airspeed [m/s] (the autopilot holds the initial one)."""
    initial = dataclasses.replace(scenario.initial, airspeed_mps=airspeed_mps)
    return dataclasses.replace(scenario, initial=initial,
                               name=f"{scenario.name}_{airspeed_mps:g}mps")


def fault_free_at(airspeeds_mps: Sequence[float], per_airspeed: int,
                  first_seed: int) -> list[Scenario]:
    """per_airspeed fault-free flights (offline.fault_free_flights: other seeds and winds)
    at each airspeed [m/s]; seeds from first_seed, none twice."""
    return [at_airspeed(scenario, airspeed)
            for k, airspeed in enumerate(airspeeds_mps)
            for scenario in fault_free_flights(per_airspeed, first_seed + per_airspeed * k,
                                               first_direction_deg=17.0 * k)]


def rates(calibration: Calibration, flight: DetectorFlight,
          false_alarm_probability: float) -> dict[str, float]:
    """Share of the flight's samples with every test running (RLS settled, GLRT window
    full) on which each test (TESTS) alarms."""
    samples = [sample for sample in run_detector(calibration, flight, false_alarm_probability)
               if np.isfinite(sample.statistic).all()]
    glrt = np.array([sample.alarm for sample in samples]).mean(axis=0)
    return {**{f"glrt_{name}": float(rate)
               for name, rate in zip(SURFACE_GENERATORS, glrt, strict=True)},
            "parameters": float(np.mean([sample.parameter_alarm for sample in samples])),
            "combined": float(np.mean([sample.combined_alarm for sample in samples]))}


def mean_rates(calibration: Calibration, flights: Sequence[DetectorFlight],
               false_alarm_probability: float) -> dict[str, float]:
    """Each test's false-alarm rate (rates()) averaged over the flights."""
    measured = [rates(calibration, flight, false_alarm_probability) for flight in flights]
    return {test: float(np.mean([m[test] for m in measured])) for test in TESTS}


def calibrated(flights: Sequence[DetectorFlight], scheduled: bool) -> Calibration:
    """calibration_fit.calibrate on the flights with the default settings of a calibration
    (the shipped ones'), with or without the airspeed schedule."""
    return calibrate(flights, scheduled=scheduled)


def compared_calibrations(flights: Sequence[DetectorFlight],
                          per_airspeed: int) -> dict[str, Calibration]:
    """The calibrations the study compares (CALIBRATIONS), from per_airspeed flights at each
    of three calibration airspeeds, in order: one_airspeed (the middle airspeed's flights
    alone), unscheduled and scheduled (all of them)."""
    middle = flights[per_airspeed:2 * per_airspeed]
    return {"one_airspeed": calibrated(middle, False),
            "unscheduled": calibrated(flights, False),
            "scheduled": calibrated(flights, True)}


def rates_per_group(calibration: Calibration, flights: Sequence[DetectorFlight],
                    group_size: int, false_alarm_probability: float) -> list[dict[str, float]]:
    """mean_rates over each run of group_size consecutive flights (one run per airspeed)."""
    return [mean_rates(calibration, flights[start:start + group_size], false_alarm_probability)
            for start in range(0, len(flights), group_size)]
