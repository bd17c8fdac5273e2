"""The estimation step mhe_node and the offline chain share: columns picked by name, the
published faults apart from nuisance columns, and a sample it cannot use refused without a
trace."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from uav_common.channels import PAPER_FAULT_NAMES
from uav_fault_estimator.estimation import estimator_step
from uav_fault_estimator.estimation.estimator_settings import EstimatorSettings
from uav_fault_estimator.estimation.estimator_step import (
    EstimatorStep,
    RejectedSampleError,
    ResidualInput,
    warm_up_text,
)
from uav_fault_estimator.estimation.noise_model import load_noise_calibration
from uav_fault_estimator.estimation.residuals import WIND_AIR_DATA

PERIOD_S, SAMPLES, TAU_A_S = 0.5, 80, 4.0
FAULTS = list(PAPER_FAULT_NAMES)


def samples(seed: int = 0) -> list[ResidualInput]:
    """Residuals of a 6 % first fault from sample 20 on, with noise, S fixed and well
    conditioned, columns in FAULTS order."""
    rng = np.random.default_rng(seed)
    sensitivity = np.eye(6, len(FAULTS)) * 0.05 + 0.005 * rng.normal(size=(6, len(FAULTS)))
    faults_pct = np.zeros(len(FAULTS))
    out = []
    for k in range(SAMPLES):
        faults_pct[0] = 6.0 if k >= 20 else 0.0
        residual = sensitivity @ faults_pct + 0.01 * rng.normal(size=6)
        out.append(ResidualInput(k * PERIOD_S, residual, np.ones(6, dtype=bool),
                                 sensitivity.ravel(), FAULTS, WIND_AIR_DATA, TAU_A_S))
    return out


def run(step: EstimatorStep, inputs: list[ResidualInput]) -> np.ndarray:
    return np.array([step.update(sample).published_pct for sample in inputs])


@pytest.mark.timeout(60)
@pytest.mark.parametrize("bad", [
    {"column_names": FAULTS[:3]},
    {"sensitivity": np.zeros(6 * len(FAULTS) + 1)},
    {"wind_source": 7},
    {"tau_a_s": float("nan")},
])
def test_a_sample_it_cannot_use_is_refused_and_changes_nothing(bad):
    inputs = samples()
    clean, tried = EstimatorStep(EstimatorSettings()), EstimatorStep(EstimatorSettings())
    expected = run(clean, inputs)
    before = run(tried, inputs[:40])
    with pytest.raises(RejectedSampleError):
        tried.update(dataclasses.replace(inputs[40], **bad))
    after = run(tried, inputs[40:])
    assert np.array_equal(np.vstack([before, after]), expected)
    assert expected[-1, 0] == pytest.approx(6.0, abs=1.0)


@pytest.mark.timeout(60)
def test_columns_are_picked_by_name_and_only_the_faults_are_published():
    """The same residuals with S's columns in another order and an extra column the
    estimator does not estimate give the same estimates; nuisance wind-error columns,
    when estimated, are not among the published faults."""
    inputs = samples()
    order = [2, 0, 3, 1]
    extra = [dataclasses.replace(
        sample, column_names=[FAULTS[j] for j in order] + ["propulsion_loss"],
        sensitivity=np.column_stack([np.reshape(sample.sensitivity, (6, -1))[:, order],
                                     np.ones(6)]).ravel()) for sample in inputs]
    expected = run(EstimatorStep(EstimatorSettings()), inputs)
    assert np.array_equal(run(EstimatorStep(EstimatorSettings()), extra), expected)
    wind_errors = ["wind_north_error", "wind_east_error", "wind_down_error"]
    with_nuisance = EstimatorStep(EstimatorSettings(estimate_wind_errors=True))
    result = with_nuisance.update(dataclasses.replace(
        inputs[0], column_names=FAULTS + wind_errors,
        sensitivity=np.column_stack([np.reshape(inputs[0].sensitivity, (6, -1)),
                                     np.zeros((6, 3))]).ravel()))
    assert list(with_nuisance.estimated_names) == FAULTS + wind_errors
    assert result.published_pct.shape == (len(FAULTS),)
    assert result.window_pct.shape[1] == len(FAULTS)


@pytest.mark.timeout(10)
def test_the_warm_up_says_the_configured_prior_window_and_settle_time():
    step = EstimatorStep(EstimatorSettings(prior_pct=(1.5, 0.0, 0.0, 0.0), horizon=80))
    text = warm_up_text(step.config)
    assert "the prior (1.5, 0, 0, 0 %) until the residuals are valid" in text
    assert "meaningful from 20 s of simulation time on" in text
    assert "the window holds the last 80 residuals" in text
    # what it says of the waiting estimates holds: the prior, until a valid residual comes
    first = step.update(dataclasses.replace(samples()[0], valid=np.zeros(6, dtype=bool)))
    np.testing.assert_array_equal(first.published_pct, [1.5, 0.0, 0.0, 0.0])


@pytest.mark.timeout(60)
def test_the_noise_calibration_is_read_once_and_a_retune_keeps_it(monkeypatch):
    """The step reads the noise file its settings name once, at setup; a retune (a live
    setting changed) takes the calibration read then and is configured as a step set up
    with the new settings."""
    reads = []

    def counted(*arguments):
        reads.append(arguments)
        return load_noise_calibration(*arguments)

    monkeypatch.setattr(estimator_step, "load_noise_calibration", counted)
    retuned = EstimatorStep(EstimatorSettings())
    run(retuned, samples()[:40])
    retuned.retune(dataclasses.replace(retuned.settings, noise_variance_factor=8.0))
    assert reads == [("", "aerosonde")]
    fresh = EstimatorStep(EstimatorSettings(noise_variance_factor=8.0))
    assert retuned.config == fresh.config
    assert retuned.noise.variance_factor == fresh.noise.variance_factor == 8.0
