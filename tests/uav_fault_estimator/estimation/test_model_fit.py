"""The model_fit status's test on residuals, and the generator's air-data bias."""

from __future__ import annotations

import numpy as np
import pytest
from uav_aircraft.flown_aircraft import FlownAircraft, SensorBias, biased_air_data, true_air_data
from uav_common.filters import SettlingLowPass
from uav_fault_estimator.estimation.model_fit import (
    ASSESSING,
    DOES_NOT_FIT,
    FITS,
    NOT_ASSESSED,
    ModelFit,
)
from uav_fault_estimator.estimation.noise_model import SUITES, NoiseCalibration
from uav_fault_estimator.estimation.residuals import WIND_AIR_DATA

PERIOD_S = 0.5
SIGMA = np.array([0.016, 0.015, 0.047, 0.18, 0.062, 0.019])  # about the shipped noise
NOISE = NoiseCalibration({suite: SIGMA**2 for suite in SUITES.values()},
                         {suite: np.zeros(6) for suite in SUITES.values()})


def run(fit: ModelFit, residuals: np.ndarray, reported: np.ndarray | None = None) -> list:
    reported = np.zeros(len(residuals), dtype=bool) if reported is None else reported
    return [fit.update(k * PERIOD_S, y, np.ones(6, dtype=bool), WIND_AIR_DATA, fault)
            for k, (y, fault) in enumerate(zip(residuals, reported, strict=True))]


def white(samples: int, seed: int = 3) -> np.ndarray:
    return np.random.default_rng(seed).standard_normal((samples, 6)) * SIGMA


def test_white_residuals_fit_and_a_bias_of_one_deviation_does_not():
    """120 white samples a minute: their mean is within 4 of its deviations; a mean of one
    noise deviation on linear_z is 11 of them (sqrt(120)) and called."""
    fit = ModelFit(NOISE, window_s=60.0, threshold_sigmas=6.0, judged_after_s=20.0)
    verdicts = run(fit, white(600))
    assert verdicts[20].verdict == ASSESSING  # 10 s: not judged yet
    assert {v.verdict for v in verdicts[60:]} == {FITS}
    assert max(abs(v.largest_sigmas) for v in verdicts[60:]) < 4.0
    biased = white(600, seed=4) + np.array([0, 0, 1.0, 0, 0, 0]) * SIGMA
    verdict = run(ModelFit(NOISE, 60.0, 6.0, 20.0), biased)[-1]
    assert verdict.verdict == DOES_NOT_FIT and verdict.channel == "linear_z"
    assert verdict.largest_sigmas == pytest.approx(np.sqrt(120), abs=4.0)
    assert "model does not fit: recalibrate" in verdict.text


def test_a_fault_reported_after_the_model_fits_is_not_the_models():
    """Judged fit first, then a fault reported: not assessed, and the fault's residuals do
    not enter the window."""
    residuals = white(400)
    residuals[200:, 0] += 5 * SIGMA[0]  # a drag-like fault from 100 s
    reported = np.zeros(400, dtype=bool)
    reported[202:] = True  # the estimator reports it 1 s later
    verdicts = run(ModelFit(NOISE, 60.0, 6.0, 20.0), residuals, reported)
    assert verdicts[199].verdict == FITS
    assert {v.verdict for v in verdicts[202:]} == {NOT_ASSESSED}


def test_a_model_error_from_take_off_is_called_though_a_fault_is_reported():
    """Reported from the start (a changed aircraft the estimator reads as a fault): the
    window is judged all the same, and says the model does not fit."""
    residuals = white(100) + np.array([0, 0, 3.0, 0, 0, 0]) * SIGMA
    verdicts = run(ModelFit(NOISE, 60.0, 6.0, 20.0), residuals, np.ones(100, dtype=bool))
    assert verdicts[-1].verdict == DOES_NOT_FIT


def test_the_settling_low_pass_starts_as_a_running_mean():
    values = np.random.default_rng(5).standard_normal(200) + 5.0
    smooth = SettlingLowPass(tau_s=30.0)
    outputs = [float(smooth.update(v, 0.05)) for v in values]
    assert outputs[99] == pytest.approx(values[:100].mean(), rel=1e-9)  # 5 s < tau
    assert abs(outputs[-1] - 5.0) < 0.25


def test_an_air_data_bias_taken_out_gives_the_true_air_data_back():
    bias = FlownAircraft(sensor_bias=SensorBias(1.03, 0.7, -0.4)).sensor_bias
    truth = np.array([24.0, 0.05, -0.01])
    assert true_air_data(biased_air_data(truth, bias), bias) == pytest.approx(truth, abs=1e-15)
