"""The ALFA-kinds study's flights and its bound on what a detector can find (the detector's
figures themselves are the study's: docs/results.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uav_fault_estimator.chain.offline import GridFlight
from uav_fault_estimator.detection.calibration import (
    Calibration,
    ChannelCalibration,
    FastTestCalibration,
)
from uav_fault_estimator.detection.change_detection import Weibull

from studies.alfa_kinds import FAULT_FREE, REQUIRED_SNR, flights, signal_to_noise, twin

PERIOD_S = 0.2
NORTH = 6  # velocity north in the state (uav_common.channels)


def level_flight_north(forces_mps2: np.ndarray) -> GridFlight:
    """A flight heading north, wings level, whose body-x specific force is forces_mps2 (K,)
    [m/s^2] at each sample after the first."""
    count = len(forces_mps2)
    states = np.zeros((count, 14))
    states[:, NORTH] = 20.0 + PERIOD_S * np.concatenate(([0.0], np.cumsum(forces_mps2[1:])))
    return GridFlight(np.arange(count) * PERIOD_S, states, np.zeros((count, 7)),
                      np.zeros((count, 7)), np.full(count, math.nan),
                      np.full((count, 3), math.nan))


def longitudinal_calibration() -> Calibration:
    channel = ChannelCalibration(np.array([0.05]), np.eye(1), np.array([0.05]), np.ones(1),
                                 Weibull(1.0, 1.0),
                                 FastTestCalibration(1.0, Weibull(1.0, 1.0)))
    return Calibration(PERIOD_S, 0.995, 25, 30.0, {"longitudinal_force": channel},
                       Weibull(1.0, 1.0))


@pytest.mark.timeout(30)
def test_each_failed_flight_has_a_twin_that_differs_by_its_failure_alone():
    table = flights("carbon_z", 1)
    kinds = [kind for kind, *_ in table]
    assert kinds[-1] == FAULT_FREE and len(set(kinds)) == len(kinds) == 7
    for kind, onset_s, scenario in table[:-1]:
        (fault,) = scenario.faults
        assert (fault.name, fault.start_s) == (kind, onset_s) and 60.0 <= onset_s <= 120.0
        flown_without = twin(scenario)
        assert flown_without.faults == () and flown_without.duration_s == scenario.duration_s
        assert (flown_without.seed, flown_without.wind) == (scenario.seed, scenario.wind)


@pytest.mark.timeout(30)
def test_the_signal_to_noise_ratio_is_the_matched_filters_over_the_five_seconds():
    """A thrust loss of 0.5 m/s^2 from 60.1 s in a residual of known spread: 25 samples in
    (60.1, 65.1] s give sqrt(25) * 0.5 / spread."""
    rng = np.random.default_rng(3)
    noise_mps2 = rng.normal(0.0, 0.1, 600)
    times_s = np.arange(600) * PERIOD_S
    loss_mps2 = np.where(times_s > 60.1, 0.5, 0.0)
    clean = level_flight_north(noise_mps2)
    failed = level_flight_north(noise_mps2 - loss_mps2)
    spread = np.std(noise_mps2[1:][times_s[1:] >= 30.0])  # the twin's residual, settled
    ratio = signal_to_noise(failed, clean, longitudinal_calibration(), 60.1)
    assert ratio == pytest.approx(5.0 * 0.5 / spread, rel=1e-9)
    assert ratio > REQUIRED_SNR  # 0.5 m/s^2 is 5 spreads: found by the bound
    assert signal_to_noise(clean, clean, longitudinal_calibration(), 60.1) == 0.0
    assert pytest.approx(1.6449 + 1.2816, abs=1e-4) == REQUIRED_SNR
