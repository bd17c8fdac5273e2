"""The detector's pieces against known answers: RLS on synthetic ARX data (eq. 9-11), the
Laplacian GLRT against its likelihoods computed directly (eq. 22), the Weibull threshold
(eq. 25) against scipy, the fast window test on white residuals and a step, and the
calibration file's round trip."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from scipy import stats
from uav_fault_estimator.detection.calibration import (
    Calibration,
    ChannelCalibration,
    FastTestCalibration,
)
from uav_fault_estimator.detection.calibration_file import (
    calibration_from_dict,
    calibration_to_dict,
    read_calibration,
)
from uav_fault_estimator.detection.change_detection import (
    SlidingGlrt,
    SlidingMeanChange,
    Weibull,
    laplacian_glrt,
    per_sample_probability,
    weibull_fit,
    weibull_threshold,
)
from uav_fault_estimator.detection.detector import SelfTuningDetector
from uav_fault_estimator.detection.generators import SURFACE_GENERATORS
from uav_fault_estimator.detection.rls import RecursiveLeastSquares


def arx_data(theta: np.ndarray, samples: int, noise: float, seed: int):
    """y[k] = a u[k] + b y[k-1] + c + e[k] (the yaw model's shape, eq. 4), u white."""
    rng = np.random.default_rng(seed)
    u = rng.normal(0.0, 1.0, samples)
    y = np.zeros(samples)
    for k in range(1, samples):
        y[k] = theta @ [u[k], y[k - 1], 1.0] + noise * rng.normal()
    return [(np.array([u[k], y[k - 1], 1.0]), y[k]) for k in range(1, samples)]


@pytest.mark.timeout(30)
@pytest.mark.parametrize("forgetting", [1.0, 0.995])
def test_rls_converges_to_the_arx_parameters(forgetting):
    theta = np.array([-0.4, 0.7, 0.05])
    rls = RecursiveLeastSquares(np.zeros(3), 100.0 * np.eye(3), forgetting)
    for phi, y in arx_data(theta, 3000, noise=0.01, seed=3):
        rls.update(phi, y)
    error = np.abs(rls.theta - theta)
    print(f"lambda_f {forgetting}: |theta - true| = {error}")
    assert error.max() < (2e-3 if forgetting == 1.0 else 1e-2)


@pytest.mark.timeout(30)
def test_rls_prediction_error_is_made_with_the_previous_parameters():
    rls = RecursiveLeastSquares(np.array([2.0, 1.0]), np.eye(2), 1.0)
    step = rls.update(np.array([3.0, 1.0]), 10.0)
    assert step.prediction_error == pytest.approx(10.0 - (2.0 * 3.0 + 1.0))  # eq. 9
    # eq. 10 in its written form, with the inverses
    p_inv = np.eye(2) + np.outer([3.0, 1.0], [3.0, 1.0])
    np.testing.assert_allclose(rls.p, np.linalg.inv(p_inv), rtol=1e-12)
    np.testing.assert_allclose(  # eq. 11
        step.theta, [2.0, 1.0] + np.linalg.inv(p_inv) @ [3.0, 1.0] * 3.0, rtol=1e-12)


def direct_glrt(x: np.ndarray) -> float:
    """log of the ratio of the Laplace likelihoods, maximised directly: under H1 by scipy's
    fit of location and scale, under H0 with the location fixed at 0."""
    location, scale = stats.laplace.fit(x)
    _, scale_h0 = stats.laplace.fit(x, floc=0.0)
    return float(np.sum(stats.laplace.logpdf(x, location, scale))
                 - np.sum(stats.laplace.logpdf(x, 0.0, scale_h0)))


@pytest.mark.timeout(30)
@pytest.mark.parametrize("shift", [0.0, 0.3, 2.0])
def test_glrt_statistic_matches_the_likelihood_ratio(shift):
    x = stats.laplace.rvs(loc=shift, scale=0.5, size=25, random_state=11)
    assert laplacian_glrt(x) == pytest.approx(direct_glrt(x), rel=1e-9, abs=1e-9)


@pytest.mark.timeout(30)
def test_sliding_glrt_waits_for_a_full_window_then_tracks_the_last_samples():
    x = stats.laplace.rvs(loc=1.0, scale=0.2, size=40, random_state=5)
    glrt = SlidingGlrt(window=25)
    values = [glrt.update(value) for value in x]
    assert values[:24] == [None] * 24
    assert values[-1] == pytest.approx(laplacian_glrt(x[-25:]))
    assert laplacian_glrt(np.zeros(5)) == 0.0


@pytest.mark.timeout(30)
def test_weibull_threshold_gives_exactly_the_false_alarm_probability():
    samples = stats.weibull_min.rvs(1.7, scale=2.3, size=5000, random_state=2)
    fitted = weibull_fit(samples)
    shape, _, scale = stats.weibull_min.fit(samples, floc=0.0)
    assert (fitted.shape, fitted.scale) == pytest.approx((shape, scale), rel=1e-12)
    assert (fitted.shape, fitted.scale) == pytest.approx((1.7, 2.3), rel=0.05)
    for p_fa in (0.1, 0.01, 1e-4):
        gamma = weibull_threshold(fitted, p_fa)  # eq. 25
        assert stats.weibull_min.sf(gamma, shape, scale=scale) == pytest.approx(p_fa, rel=1e-10)
        assert gamma == pytest.approx(stats.weibull_min.isf(p_fa, shape, scale=scale),
                                      rel=1e-10)
        assert fitted.survival(gamma) == pytest.approx(p_fa, rel=1e-12)  # eq. 24
    with pytest.raises(ValueError, match="P_FA"):
        weibull_threshold(fitted, 0.0)
    with pytest.raises(ValueError, match="at least 10"):
        weibull_fit(np.zeros(100))


def small_calibration() -> Calibration:
    channels = {name: ChannelCalibration(
        np.full(n, 0.5), np.eye(n), np.zeros(n), np.ones(n), Weibull(2.0, 1.5),
        FastTestCalibration(0.1, Weibull(1.2, 1.4)))
        for name, n in (("roll", 2), ("pitch", 2), ("yaw", 3))}
    return Calibration(0.2, 0.995, 25, 30.0, channels, Weibull(1.5, 2.5))


@pytest.mark.timeout(30)
def test_calibration_round_trip_and_a_malformed_one():
    calibration = small_calibration()
    again = calibration_from_dict(calibration_to_dict(calibration))
    assert calibration_to_dict(again) == calibration_to_dict(calibration)
    broken = calibration_to_dict(calibration)
    broken["channels"]["yaw"]["theta0"] = [1.0, 2.0]
    with pytest.raises(ValueError, match="channel yaw"):
        calibration_from_dict(broken)


@pytest.mark.timeout(30)
def test_detector_skips_non_finite_samples_and_keeps_its_parameters():
    detector = SelfTuningDetector(small_calibration(), false_alarm_probability=0.01)
    assert detector.thresholds == pytest.approx([2.0 * (-math.log(0.01)) ** (1 / 1.5)] * 3)
    state, controls = np.zeros(14), np.zeros(7)
    assert detector.update(0.0, state, controls) is None  # the first: no r[k-1] yet
    assert detector.update(0.1, state, controls) is None  # off the 0.2 s grid
    sample = detector.update(0.2, state, controls)
    assert sample is not None and list(sample.theta) == list(SURFACE_GENERATORS)
    assert np.isnan(sample.statistic).all()  # not settled yet
    theta = {name: rls.theta.copy() for name, rls in detector.rls.items()}
    state[9] = math.nan  # roll rate lost
    assert detector.update(0.4, state, controls) is None
    assert all(np.array_equal(detector.rls[name].theta, theta[name]) for name in SURFACE_GENERATORS)


@pytest.mark.timeout(30)
def test_a_new_false_alarm_probability_moves_the_thresholds_and_keeps_the_generators():
    detector = SelfTuningDetector(small_calibration(), false_alarm_probability=0.01)
    state, controls = np.zeros(14), np.zeros(7)
    for k in range(5):
        detector.update(0.2 * k, state, controls)
    theta = {name: rls.theta.copy() for name, rls in detector.rls.items()}
    detector.set_false_alarm_probability(1e-4)
    assert detector.thresholds == pytest.approx([2.0 * (-math.log(1e-4)) ** (1 / 1.5)] * 3)
    assert detector.parameter_threshold == pytest.approx(1.5 * (-math.log(1e-4)) ** (1 / 2.5))
    assert all(np.array_equal(detector.rls[name].theta, theta[name]) for name in SURFACE_GENERATORS)
    sample = detector.update(1.0, state, controls)
    assert sample is not None and sample.threshold == pytest.approx(detector.thresholds)


@pytest.mark.timeout(30)
def test_the_window_change_is_standard_on_white_residuals_and_follows_a_step():
    rng = np.random.default_rng(3)
    std, window, reference = 0.5, 15, 150
    test = SlidingMeanChange(window, reference, std)
    # an offset of the residuals' mean (a new day's bias) does not move it
    white = [test.update(x) for x in rng.normal(2.0, std, 20_000)]
    assert white[:window + reference - 1] == [None] * (window + reference - 1)
    z = np.array(white[window + reference - 1:])
    # N(0, 1): mean 0; its size mean sqrt(2/pi), 5 % above 1.96
    assert abs(z.mean()) < 0.1
    assert np.abs(z).mean() == pytest.approx(math.sqrt(2 / math.pi), rel=0.05)
    assert (np.abs(z) > 1.96).mean() == pytest.approx(0.05, abs=0.01)
    # a step of the mean by d: after a full window of it, |d| / std / sqrt(1/W + 1/R)
    step = SlidingMeanChange(window, reference, std)
    for x in rng.normal(0.0, std, reference):
        step.update(x)
    after = [step.update(x) for x in rng.normal(-0.4, std, window)][-1]
    assert after == pytest.approx(-0.4 / std / math.sqrt(1 / window + 1 / reference), abs=3.0)
    with pytest.raises(ValueError, match="spread"):
        SlidingMeanChange(window, reference, 0.0)


@pytest.mark.timeout(30)
def test_a_rate_per_hour_is_a_probability_per_sample_of_a_window():
    # 1 per hour, 15 samples of 0.2 s: 1 * 15 * 0.2 / 3600
    assert per_sample_probability(1.0, 15, 0.2) == pytest.approx(15 * 0.2 / 3600)
    assert per_sample_probability(1e6, 15, 0.2) == 0.5
    with pytest.raises(ValueError, match="per hour"):
        per_sample_probability(0.0, 15, 0.2)


@pytest.mark.timeout(30)
def test_the_fast_test_alarms_within_its_window_of_a_step_the_rls_would_absorb():
    """A roll channel p = a da + b, the calibration's a = b = 0.5 fixed: a step of b by 10
    residual spreads after the detector settled raises the fast test within its window, and
    the alarm names the roll channel's kind; the thresholds follow the designed rate per
    hour."""
    calibration = small_calibration()
    detector = SelfTuningDetector(calibration, 0.01, fast_false_alarms_per_hour=2.0)
    probability = per_sample_probability(2.0, calibration.fast_window, 0.2)
    assert detector.fast_thresholds == pytest.approx(
        [weibull_threshold(Weibull(1.2, 1.4), probability)] * 3)
    rng = np.random.default_rng(4)
    state, controls = np.zeros(14), np.zeros(7)
    step_s, first_s = 40.0, None
    for k in range(1, 300):
        time_s = 0.2 * k
        controls[2] = rng.normal(0.0, 0.1)  # aileron
        bias = 0.5 + (1.0 if time_s >= step_s else 0.0)
        state[9] = 0.5 * controls[2] + bias + rng.normal(0.0, 0.1)  # roll rate
        state[11] = 0.5 * controls[2] + 0.5 * state[11] + 0.5  # yaw rate, as calibrated
        sample = detector.update(time_s, state, controls)
        if sample is not None and sample.fast_alarm[0] and first_s is None:
            first_s = time_s
            assert sample.combined_alarm and not sample.fast_alarm[2]
            assert sample.cause == "aileron"  # the roll channel's kind
    assert step_s <= first_s < step_s + calibration.fast_window * 0.2


@pytest.mark.timeout(30)
def test_a_calibration_without_the_fast_test_is_refused_in_one_line(tmp_path):
    data = calibration_to_dict(small_calibration())
    del data["fast_window"]
    path = tmp_path / "old.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ValueError, match=r"holds no fast test.*calibrate again"):
        read_calibration(str(path), data["airframe"])
