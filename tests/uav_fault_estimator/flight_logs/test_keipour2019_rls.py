"""The peer (flight_logs/keipour2019_rls.py) on pairs whose relation is known: its RLS learns a
command-to-response relation within the warm-up, its residual stays near the noise while the
relation holds and rises when the response stops following the command; its thresholds
come from the calibration flights' fault-free parts, and its alarms are counted by the
project's evaluation."""

from __future__ import annotations

import numpy as np
import pytest
from uav_fault_estimator.flight_logs import keipour2019_rls as peer
from uav_fault_estimator.flight_logs.ground_truth import NO_FAILURE, FlightTruth

START_S = 1531900000.0
NOISE = 0.002  # [rad or m/s] of the measured output


def synthetic_pairs(seed: int, duration_s: float = 60.0, cut_at_s: float | None = None):
    """Commands (K, P) and responses (K, P) at RATE_HZ: each response a lagged, scaled copy
    of its command plus noise; from cut_at_s on the response stops following (held)."""
    rng = np.random.default_rng(seed)
    times_s = np.arange(0.0, duration_s, 1.0 / peer.RATE_HZ)
    phase = rng.uniform(0, 2 * np.pi, len(peer.PAIRS))
    command = 0.2 * np.sin(0.5 * times_s[:, None] + phase) + 0.1 * np.sin(
        1.3 * times_s[:, None] + 2 * phase)
    response = 0.6 * np.roll(command, 3, axis=0) + 0.3 * np.roll(command, 5, axis=0)
    response += NOISE * rng.standard_normal(response.shape)
    if cut_at_s is not None:
        cut = np.searchsorted(times_s, cut_at_s)
        response[cut:] = response[cut]
    return times_s, command, response


def flight(name: str, seed: int, truth: FlightTruth, cut_at_s: float | None = None):
    times_s, command, response = synthetic_pairs(seed, cut_at_s=cut_at_s)
    return peer.PeerFlight(name, truth, START_S + times_s,
                           peer.prediction_residuals(times_s, command, response))


@pytest.mark.timeout(60)
def test_the_rls_learns_the_relation_and_its_residual_is_the_noise() -> None:
    quiet = flight("quiet", 1, NO_FAILURE)
    after_warm_up = quiet.residuals[~np.isnan(quiet.residuals[:, 0])]
    assert np.isnan(quiet.residuals[:int(peer.WARM_UP_S * peer.RATE_HZ) - 1]).all()
    assert after_warm_up.shape[0] > 0.8 * (60.0 - peer.WARM_UP_S) * peer.RATE_HZ
    assert np.sqrt(np.mean(after_warm_up ** 2)) < 3 * NOISE


@pytest.mark.timeout(60)
def test_a_response_that_stops_following_alarms_within_a_second() -> None:
    calibration = [flight(f"quiet_{seed}", seed, NO_FAILURE) for seed in range(6)]
    threshold = peer.thresholds(calibration)
    assert threshold.shape == (len(peer.PAIRS),) and (threshold < 10 * NOISE).all()
    cut = flight("cut", 7, FlightTruth("aileron", START_S + 40.0), cut_at_s=40.0)
    outcome = peer.outcome(cut, threshold)
    assert outcome.outcome == "tp" and outcome.delay_s < 1.0, outcome
    assert outcome.first_alarm_channel in peer.CHANNELS


@pytest.mark.timeout(60)
def test_the_folds_threshold_from_the_other_flights_only() -> None:
    """A flight whose fault-free part is noisy raises the others' thresholds, not its own:
    it alarms on a threshold the quiet flights set."""
    quiet = [flight(f"quiet_{seed}", seed, NO_FAILURE) for seed in range(2)]
    noisy = flight("noisy", 5, NO_FAILURE)
    noisy = peer.PeerFlight(noisy.name, noisy.truth, noisy.stamps_s, 5 * noisy.residuals)
    flights = [*quiet, noisy]
    outcomes = peer.screened_in_folds(flights, [([0], [1, 2]), ([1], [0, 2]), ([2], [0, 1])])
    assert [o.outcome for o in outcomes] == ["tn", "tn", "fp"]
