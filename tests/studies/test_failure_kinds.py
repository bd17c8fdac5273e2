"""The failure-kinds study's flights and its bound on what a detector can find (the
detector's figures themselves are the study's: docs/results.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uav_common.channels import ACTUATOR_FAULT_NAMES, MODEL_FAULT_NAMES
from uav_fault_estimator.chain.failure_flights import FAULT_FREE, RAMP_S, failure_flights
from uav_fault_estimator.chain.offline import GridFlight
from uav_fault_estimator.detection.calibration import (
    Calibration,
    ChannelCalibration,
    FastTestCalibration,
)
from uav_fault_estimator.detection.change_detection import Weibull
from uav_fault_estimator.detection.detector import fixed_residuals, run_detector

from studies.failure_kinds import REQUIRED_SNR, bound, found_by_sliding_bound

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
def test_each_failed_flight_has_a_twin_that_differs_by_its_fault_alone():
    table = failure_flights("carbon_z", 2, 501)
    twins = [flight for flight in table if flight.kind == FAULT_FREE]
    assert [flight.twin for flight in twins] == [0, 1] and table[:2] == twins
    kinds = list(dict.fromkeys(flight.kind for flight in table[2:]))
    assert kinds == [*ACTUATOR_FAULT_NAMES, *(f"{name}_{shape}" for name in MODEL_FAULT_NAMES
                                              for shape in ("step", "ramp"))]
    for flight in table[2:]:
        (fault,) = flight.scenario.faults
        twin = twins[flight.twin].scenario
        assert fault.start_s == flight.onset_s and 60.0 <= flight.onset_s <= 120.0
        assert twin.faults == () and twin.duration_s >= flight.scenario.duration_s
        assert (twin.seed, twin.wind) == (flight.scenario.seed, flight.scenario.wind)
        assert fault.value_pct(flight.reference_s) == pytest.approx(
            2.0 if flight.kind.endswith("_ramp") else fault.magnitude_pct)
        assert fault.ramp_s == (RAMP_S if flight.kind.endswith("_ramp") else 0.0)


@pytest.mark.timeout(30)
def test_the_study_refuses_a_kind_it_does_not_know_in_one_line():
    with pytest.raises(ValueError, match="kinds left_wing_lift: expected some of"):
        failure_flights("aerosonde", 1, 501, kinds=("engine_cut", "left_wing_lift"))


@pytest.mark.timeout(30)
def test_the_bound_is_the_matched_filters_signal_to_noise_ratio_and_its_delay():
    """A thrust loss of 0.5 m/s^2 from 60.1 s in a residual of known spread: 25 samples in
    (60.1, 65.1] s give sqrt(25) * 0.5 / spread, and the bound's delay is the first sample
    whose running ratio reaches REQUIRED_SNR."""
    rng = np.random.default_rng(3)
    noise_mps2 = rng.normal(0.0, 0.1, 600)
    times_s = np.arange(600) * PERIOD_S
    loss_mps2 = np.where(times_s > 60.1, 0.5, 0.0)
    calibration = longitudinal_calibration()
    clean, failed = (fixed_residuals(run_detector(calibration, level_flight_north(forces)
                                                  .detector_flight, 0.01))
                     for forces in (noise_mps2, noise_mps2 - loss_mps2))
    spread = np.std(noise_mps2[1:][times_s[1:] >= 30.0])  # the twin's residual, settled
    ratio, delay_s = bound(failed, clean, 30.0, 60.1)
    assert ratio == pytest.approx(5.0 * 0.5 / spread, rel=1e-9)
    samples = math.ceil((REQUIRED_SNR * spread / 0.5) ** 2)  # the running ratio's first reach
    assert delay_s == pytest.approx(samples * PERIOD_S - 0.1, abs=1e-9)
    assert ratio > REQUIRED_SNR  # 0.5 m/s^2 is 5 spreads: found by the bound
    assert bound(clean, clean, 30.0, 60.1) == (0.0, None)
    assert pytest.approx(1.6449 + 1.2816, abs=1e-4) == REQUIRED_SNR


@pytest.mark.timeout(30)
def test_the_sliding_bound_finds_a_loss_above_every_fault_free_flights_largest_value():
    """A thrust loss from 60.1 s in white residuals of spread 0.1, ten fault-free flights:
    0.5 and 0.1 m/s^2 (25 and 5 spreads over 5 s) rise above the largest value the filter
    reaches on any of them, 0.06 m/s^2 (3 spreads: detectable by the twin bound, which
    allows a 5 % false-alarm rate) does not."""
    rng = np.random.default_rng(5)
    noises = [rng.normal(0.0, 0.1, 600) for _ in range(10)]
    times_s = np.arange(600) * PERIOD_S
    calibration = longitudinal_calibration()

    def residuals(forces):
        return fixed_residuals(run_detector(calibration, level_flight_north(forces)
                                            .detector_flight, 0.01))

    fault_free = [residuals(noise) for noise in noises]
    for loss_mps2, found in ((0.5, True), (0.1, True), (0.06, False)):
        failed = residuals(noises[0] - np.where(times_s > 60.1, loss_mps2, 0.0))
        assert bound(failed, fault_free[0], 30.0, 60.1)[0] >= REQUIRED_SNR
        assert found_by_sliding_bound(failed, fault_free[0], fault_free, 30.0, 60.1, 150) \
            is found, loss_mps2
