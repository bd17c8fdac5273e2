"""One fault-estimation step per residual sample: what mhe_node does with each Residuals
message and the offline chain with each residual sample, without ROS.

Per sample: the estimated columns picked from the sample's S by name, Q from the sample's
sensor suite (or a hold, noise_model.SuiteNoise), one moving-horizon update (mhe.py), and
the model_fit verdict (model_fit.py) on the residual while no fault is reported.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from uav_common.channels import DETECTION_THRESHOLD_PCT

from uav_fault_estimator.estimation.air_data_estimate import AirDataEstimate, estimate_air_data
from uav_fault_estimator.estimation.estimator_config import EstimatorConfig
from uav_fault_estimator.estimation.estimator_settings import (
    EstimatorSettings,
    config_from_settings,
)
from uav_fault_estimator.estimation.mhe import (
    EstimateResult,
    MovingHorizonEstimator,
    median_period_s,
    missing_samples,
)
from uav_fault_estimator.estimation.model_fit import FitVerdict, ModelFit
from uav_fault_estimator.estimation.noise_model import (
    SUITES,
    SuiteNoise,
    load_noise_calibration,
)
from uav_fault_estimator.estimation.residuals import (
    RESIDUAL_CHANNELS,
    WIND_ERROR_NAMES,
    WIND_PITOT,
)
from uav_fault_estimator.estimation.solve_status import SolveStatus

# The estimator has settled this long [s of sim time] after the first residual: errors are
# judged from here (metrics.json's settle_s), and model_fit first judges a window this long.
SETTLE_S = 20.0


class RejectedSampleError(ValueError):
    """A residual sample the step cannot use (columns missing, S's size, the suite)."""


@dataclass(frozen=True)
class ResidualInput:
    """One residual sample as the step takes it: time_s [s]; residual (6,) and valid (6,)
    in RESIDUAL_CHANNELS order; sensitivity (6 * p,) row-major, or (6, p), its columns
    named by column_names; wind_source (noise_model.SUITES key) and the residual filter's
    time constant tau_a_s [s] (how long a residual remembers the wind it flew); what the
    newest sample's models flew, for synthetic air data (air_data_estimate.py): the wind
    (3,) [m/s, NED], the air velocity (3,) [m/s, body axes], the attitude (3,) [rad]
    (None: not given)."""

    time_s: float
    residual: np.ndarray
    valid: np.ndarray
    sensitivity: np.ndarray
    column_names: Sequence[str]
    wind_source: int
    tau_a_s: float
    wind_flown_ned_mps: np.ndarray | None = None
    air_velocity_body_mps: np.ndarray | None = None
    attitude_rad: np.ndarray | None = None


@dataclass(frozen=True)
class StepResult:
    """What one step gives: the estimator's result, the published faults' estimates
    (published_names order) [%] and their window (N, n) [%], the window's span horizon_s
    [s], the model_fit verdict, and the synthetic air data (None unless the wind errors
    are estimated, the sample flew a pitot without vanes and its estimate was solved)."""

    estimate: EstimateResult
    published_pct: np.ndarray
    window_pct: np.ndarray
    horizon_s: float
    fit: FitVerdict
    air_data: AirDataEstimate | None = None


def warm_up_text(config: EstimatorConfig) -> str:
    """What the first estimates are, in one line (mhe_node says it at start, so that a
    flight in real time does not look stuck): the prior until the residuals are valid, and
    meaningful from SETTLE_S of simulation time on."""
    faults = sum(fault.name not in WIND_ERROR_NAMES for fault in config.faults)
    prior = ", ".join(f"{value:g}" for value in config.prior_pct[:faults])
    return (f"the estimates are the prior ({prior} %) until the residuals are valid "
            f"(residual_node's recovery_s after the start), and meaningful from {SETTLE_S:g} s "
            f"of simulation time on (settled; the window holds the last {config.horizon} "
            "residuals); a simulator flying in real time takes as many wall seconds")


def fault_reported(estimates_pct: np.ndarray) -> bool:
    """Whether any of the estimates [%] is at or above the detection threshold."""
    return bool(np.size(estimates_pct)) and float(np.max(estimates_pct)) >= (
        DETECTION_THRESHOLD_PCT)


class EstimatorStep:
    """mhe_node's estimator from its settings, one step per residual sample; reset for a
    new flight, retune for changed live settings. The noise calibration the settings name
    is read once, here (ValueError naming the file, or the first wrong setting)."""

    def __init__(self, settings: EstimatorSettings) -> None:
        self.settings = settings
        self.noise_calibration = load_noise_calibration(settings.noise_calibration_file,
                                                        settings.vehicle)
        self.published_names = list(settings.fault_names)
        self.estimator = MovingHorizonEstimator(
            config_from_settings(settings, self.noise_calibration))
        self.estimated_names = self.estimator.column_names  # faults, then any nuisance
        self.noise = SuiteNoise(self.noise_calibration, settings.noise_variance_factor)
        self.model_fit = ModelFit(self.noise_calibration, settings.model_fit_window_s,
                                  settings.model_fit_threshold_sigmas, SETTLE_S)
        self.window_stamps_s: deque[float] = deque(maxlen=self.estimator.config.horizon)

    @property
    def config(self) -> EstimatorConfig:
        """The estimator's configuration (estimator_config.EstimatorConfig)."""
        return self.estimator.config

    def reset(self, prior_pct: np.ndarray | None = None) -> None:
        """A new flight: everything from scratch, the estimates from prior_pct (the
        estimated columns' order) [%] when given, else the configured prior."""
        self.estimator.reset(prior_pct)
        self.noise.reset()
        self.model_fit.reset()
        self.window_stamps_s.clear()

    def retune(self, settings: EstimatorSettings) -> None:
        """Apply settings whose live ones changed from the next sample on (ValueError:
        none); the noise calibration is the one read at start."""
        self.estimator.retune(config_from_settings(settings, self.noise_calibration))
        self.noise.variance_factor = settings.noise_variance_factor
        self.settings = settings

    def bridge(self, gap_s: float) -> None:
        """A gap of gap_s [s] in the samples: the window moves on by the samples missed."""
        self.estimator.advance(missing_samples(gap_s, self.window_stamps_s))

    def columns(self, sample: ResidualInput) -> list[int | None]:
        """Indices of the estimated columns among the sample's (None for a wind error the
        residuals do not carry: a source that computes none says nothing of them, as vanes
        do); RejectedSampleError saying why when a fault's column is absent, S's size does
        not match its names, the suite is unknown or the filter time constant is not a
        time."""
        offered = list(sample.column_names)
        missing = [name for name in self.estimated_names
                   if name not in offered and name not in WIND_ERROR_NAMES]
        if missing:
            raise RejectedSampleError(f"residuals lack the columns {missing}")
        if np.size(sample.sensitivity) != len(RESIDUAL_CHANNELS) * len(offered):
            raise RejectedSampleError(f"S has {np.size(sample.sensitivity)} entries for "
                                 f"{len(offered)} faults")
        if sample.wind_source not in SUITES:
            raise RejectedSampleError(f"unknown wind_source {sample.wind_source}")
        if not (math.isfinite(sample.tau_a_s) and sample.tau_a_s >= 0):
            raise RejectedSampleError(f"filter time constant {sample.tau_a_s} s")
        return [offered.index(name) if name in offered else None
                for name in self.estimated_names]

    def update(self, sample: ResidualInput) -> StepResult:
        """One estimator update with the sample (RejectedSampleError, nothing changed, when it
        cannot be used), its model_fit verdict."""
        columns = self.columns(sample)
        offered = np.reshape(sample.sensitivity, (len(RESIDUAL_CHANNELS), -1))
        sensitivity = np.zeros((len(RESIDUAL_CHANNELS), len(columns)))
        for j, column in enumerate(columns):
            if column is not None:
                sensitivity[:, j] = offered[:, column]
        q_diag = self.noise.weigh(sample.time_s, sample.wind_source, sample.tau_a_s)
        estimate = self.estimator.hold() if q_diag is None else self.estimator.update(
            np.asarray(sample.residual), sensitivity, np.asarray(sample.valid),
            q_diag)
        self.window_stamps_s.append(sample.time_s)
        published = estimate.columns(self.published_names)
        published_pct = estimate.fault_pct[published]
        fit = self.model_fit.update(sample.time_s, np.asarray(sample.residual),
                                    np.asarray(sample.valid), sample.wind_source,
                                    fault_reported(published_pct))
        return StepResult(estimate, published_pct, estimate.window_pct[:, published],
                          self.window_stamps_s[-1] - self.window_stamps_s[0], fit,
                          self.air_data(sample, estimate))

    def air_data(self, sample: ResidualInput, estimate: EstimateResult) -> AirDataEstimate | None:
        """The synthetic air data of the sample (StepResult.air_data). Its wind error's
        covariance: the estimator's (MovingHorizonEstimator.newest_covariance), plus what
        the error moves within F_a's memory, which the residuals see only as its mean: the
        Gauss-Markov steps of tau_a / (sample period) samples."""
        period_s = median_period_s(self.window_stamps_s)
        if (sample.wind_source != WIND_PITOT or estimate.status is not SolveStatus.SOLVED
                or sample.air_velocity_body_mps is None or not period_s
                or not set(WIND_ERROR_NAMES) <= set(self.estimated_names)):
            return None
        columns = estimate.columns(WIND_ERROR_NAMES)
        within_filter = (self.settings.wind_error_sigma_mps**2 * sample.tau_a_s
                         / period_s) * np.eye(len(columns))
        return estimate_air_data(
            np.asarray(sample.wind_flown_ned_mps), np.asarray(sample.air_velocity_body_mps),
            np.asarray(sample.attitude_rad), estimate.fault_pct[columns],
            self.estimator.newest_covariance(columns) + within_filter)
