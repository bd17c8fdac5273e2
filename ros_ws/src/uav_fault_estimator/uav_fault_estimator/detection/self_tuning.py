"""Self-tuning residual generators and the combined alarm (Blanke & Hansen).

Three generic models, each identified in flight by recursive least squares (rls.py) from
parameters learned on earlier fault-free flights (the calibration):

    roll   p[k] = a_pa da[k] + b_pa                    (eq. 2, residual eq. 12)
    pitch  q[k] = a_qe de[k] + b_qe                    (eq. 3, residual eq. 13)
    yaw    r[k] = a_ra da[k] + b_ra r[k-1] + c_ra      (eq. 4, residual eq. 14)

p, q, r body rates [rad/s], da aileron, de elevator [rad], sampled every sample_period_s
(the paper's 5 Hz). Per channel, on every sample: the residual is the RLS prediction error
(eq. 9), its GLRT statistic over the last M samples (change_detection.py, eq. 22) against
the threshold for the designed false-alarm probability (eq. 25, Weibull of the statistic on
fault-free flights), and the parameter deviation: the largest |theta_i - mean_i| / std_i
against the fault-free spread (section III.C), whose threshold comes from a Weibull fit of
the same statistic on the same flights, for the same P_FA. The combined alarm (section
III.D) is raised when some channel's GLRT and parameter tests agree. No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from uav_sim.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_sim.paths import config_path
from uav_sim.sample_grid import on_grid

from uav_fault_estimator.detection.change_detection import (
    SlidingGlrt,
    Weibull,
    weibull_fit,
    weibull_threshold,
)
from uav_fault_estimator.detection.rls import RecursiveLeastSquares

CHANNELS = ("roll", "pitch", "yaw")
PARAMETER_NAMES = {
    "roll": ("a_pa", "b_pa"),
    "pitch": ("a_qe", "b_qe"),
    "yaw": ("a_ra", "b_ra", "c_ra"),
}
_P, _Q, _R = (STATE_CHANNELS.index(name) for name in ("roll_rate", "pitch_rate", "yaw_rate"))
_AILERON, _ELEVATOR = (CONTROL_CHANNELS.index(name) for name in ("aileron", "elevator"))


def regressions(state: np.ndarray, controls: np.ndarray,
                previous_yaw_rate: float) -> dict[str, tuple[np.ndarray, float]]:
    """(phi, y) of each generator (eq. 5-8) from one state and controls sample."""
    aileron, elevator = controls[_AILERON], controls[_ELEVATOR]
    return {
        "roll": (np.array([aileron, 1.0]), state[_P]),
        "pitch": (np.array([elevator, 1.0]), state[_Q]),
        "yaw": (np.array([aileron, previous_yaw_rate, 1.0]), state[_R]),
    }


@dataclass(frozen=True)
class ChannelCalibration:
    """What fault-free flights taught of one generator: initial parameters theta0 and
    covariance P0 of the RLS, the parameters' mean and standard deviation in flight, and
    the Weibull distribution of its GLRT statistic."""

    theta0: np.ndarray
    p0: np.ndarray
    parameter_mean: np.ndarray
    parameter_std: np.ndarray
    glrt: Weibull


@dataclass(frozen=True)
class Calibration:
    """The detector's calibration; valid for its sample period, forgetting factor and
    GLRT window only (the statistics' distributions depend on them)."""

    sample_period_s: float
    forgetting_factor: float
    window: int
    settle_s: float  # after a (re)start, no test until the RLS has had this long
    channels: Mapping[str, ChannelCalibration]
    parameter: Weibull  # of the largest normalised parameter deviation over the channels

    def to_dict(self) -> dict[str, Any]:
        return {
            "sample_period_s": self.sample_period_s,
            "forgetting_factor": self.forgetting_factor,
            "window": self.window,
            "settle_s": self.settle_s,
            "parameter_deviation_weibull": _weibull_dict(self.parameter),
            "channels": {name: {
                "parameters": list(PARAMETER_NAMES[name]),
                "theta0": c.theta0.tolist(), "p0": c.p0.tolist(),
                "parameter_mean": c.parameter_mean.tolist(),
                "parameter_std": c.parameter_std.tolist(),
                "glrt_weibull": _weibull_dict(c.glrt),
            } for name, c in self.channels.items()},
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Calibration:
        """From to_dict()'s layout; KeyError or ValueError on a malformed one."""
        channels = {}
        for name in CHANNELS:
            c = data["channels"][name]
            n = len(PARAMETER_NAMES[name])
            arrays = [np.array(c[key], dtype=float) for key in
                      ("theta0", "p0", "parameter_mean", "parameter_std")]
            if [a.shape for a in arrays] != [(n,), (n, n), (n,), (n,)]:
                raise ValueError(f"channel {name}: arrays must be {n}, {n}x{n}, {n}, {n}")
            channels[name] = ChannelCalibration(*arrays, glrt=Weibull(**c["glrt_weibull"]))
        return cls(float(data["sample_period_s"]), float(data["forgetting_factor"]),
                   int(data["window"]), float(data["settle_s"]), channels,
                   Weibull(**data["parameter_deviation_weibull"]))


def _weibull_dict(distribution: Weibull) -> dict[str, float]:
    return {"scale": distribution.scale, "shape": distribution.shape}


def parameter_deviation(theta: np.ndarray, channel: ChannelCalibration) -> np.ndarray:
    """The largest |theta_i - mean_i| / std_i over a channel's parameters (section III.C);
    theta (n,) or (K, n) for K samples."""
    return np.max(np.abs(theta - channel.parameter_mean) / channel.parameter_std, axis=-1)


@dataclass(frozen=True)
class DetectorSample:
    """One detector step: per channel (CHANNELS order) residual, GLRT statistic (NaN while
    the window fills or the RLS settles), threshold, alarm and parameter deviation; the
    parameter threshold and alarm; the combined alarm; each channel's parameters."""

    time_s: float
    residual: np.ndarray
    statistic: np.ndarray
    threshold: np.ndarray
    alarm: np.ndarray
    parameter_deviation: np.ndarray
    parameter_threshold: float
    parameter_alarm: bool
    combined_alarm: bool
    theta: dict[str, np.ndarray]


class SelfTuningDetector:
    """Feed it every state/controls sample; it acts on the calibration's sample grid."""

    def __init__(self, calibration: Calibration, false_alarm_probability: float) -> None:
        self.calibration = calibration
        self.set_false_alarm_probability(false_alarm_probability)
        # Samples on the grid that could not be used (the first after a reset; a rate or
        # surface missing), over the detector's life.
        self.skipped_samples = 0
        self.reset()

    def set_false_alarm_probability(self, false_alarm_probability: float) -> None:
        """The thresholds of every test for this designed false-alarm probability per sample
        (eq. 25), from the next sample on; the generators' state is kept."""
        calibration = self.calibration
        self.false_alarm_probability = false_alarm_probability
        self.thresholds = np.array([weibull_threshold(calibration.channels[c].glrt,
                                                      false_alarm_probability)
                                    for c in CHANNELS])
        self.parameter_threshold = weibull_threshold(calibration.parameter,
                                                     false_alarm_probability)

    def reset(self) -> None:
        """Back to the calibration's parameters: after a restart of the source."""
        c = self.calibration
        self.rls = {name: RecursiveLeastSquares(c.channels[name].theta0, c.channels[name].p0,
                                                c.forgetting_factor) for name in CHANNELS}
        self.glrt = {name: SlidingGlrt(c.window) for name in CHANNELS}
        self.previous_yaw_rate: float | None = None
        self.started_s: float | None = None

    def update(self, time_s: float, state: np.ndarray,
               controls: np.ndarray) -> DetectorSample | None:
        """One sample (state and controls arrays, uav_sim.channels order). None off the grid,
        for the first sample (the yaw model needs r[k-1]), and for a sample with a
        non-finite value it needs (skipped: the RLS keeps its parameters)."""
        if not on_grid(time_s, self.calibration.sample_period_s):
            return None
        rates = state[[_P, _Q, _R]]
        surfaces = controls[[_AILERON, _ELEVATOR]]
        if not (np.all(np.isfinite(rates)) and np.all(np.isfinite(surfaces))):
            self.skipped_samples += 1
            return None
        previous, self.previous_yaw_rate = self.previous_yaw_rate, float(state[_R])
        if previous is None:
            self.started_s = time_s
            self.skipped_samples += 1
            return None
        settled = time_s - self.started_s >= self.calibration.settle_s
        regression = regressions(state, controls, previous)
        residual, statistic, deviation, theta = [], [], [], {}
        for name in CHANNELS:
            step = self.rls[name].update(*regression[name])
            channel = self.calibration.channels[name]
            g = self.glrt[name].update(step.prediction_error)
            residual.append(step.prediction_error)
            statistic.append(g if g is not None and settled else math.nan)
            deviation.append(float(parameter_deviation(step.theta, channel))
                             if settled else math.nan)
            theta[name] = step.theta
        statistic, deviation = np.array(statistic), np.array(deviation)
        alarm = statistic > self.thresholds  # NaN compares False
        deviates = deviation > self.parameter_threshold
        return DetectorSample(
            time_s=time_s, residual=np.array(residual), statistic=statistic,
            threshold=self.thresholds.copy(), alarm=alarm, parameter_deviation=deviation,
            parameter_threshold=self.parameter_threshold,
            parameter_alarm=bool(deviates.any()),
            combined_alarm=bool(np.any(alarm & deviates)), theta=theta,
        )


def shipped_calibration_path() -> Path:
    """The package's config/detector_calibration.yaml (scripts/calibrate_detector.py)."""
    return config_path("uav_fault_estimator", "detector_calibration.yaml")


def load_calibration(path: str, window: int, forgetting_factor: float) -> Calibration:
    """The calibration file (empty path: the shipped one), checked against the node's
    window and forgetting factor; ValueError with one line naming the file."""
    file = Path(path) if path else shipped_calibration_path()
    try:
        calibration = Calibration.from_dict(yaml.safe_load(file.read_text()))
    except (OSError, yaml.YAMLError, KeyError, TypeError, ValueError) as error:
        raise ValueError(f"calibration file {file}: {type(error).__name__}: {error}") from None
    if calibration.window != window or not math.isclose(calibration.forgetting_factor,
                                                         forgetting_factor):
        raise ValueError(
            f"calibration file {file} was made for window {calibration.window} and "
            f"forgetting factor {calibration.forgetting_factor}, not {window} and "
            f"{forgetting_factor}: run scripts/calibrate_detector.py for these")
    return calibration


# --- calibration from fault-free flights ---------------------------------------------


def fit_initial_parameters(flights: Iterable[tuple[np.ndarray, np.ndarray]],
                           forgetting_factor: float) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """theta0 and P0 per channel from flights given as (states (K, n), controls (K, m)) on
    the sample grid: theta0 the least-squares fit over all their samples, P0 the RLS
    covariance it settles to on such data, (1 - lambda_f) (Phiᵀ Phi / K)^-1."""
    rows: dict[str, list] = {name: [] for name in CHANNELS}
    targets: dict[str, list] = {name: [] for name in CHANNELS}
    for states, controls in flights:
        for k in range(1, len(states)):
            for name, (phi, y) in regressions(states[k], controls[k],
                                               states[k - 1, _R]).items():
                rows[name].append(phi)
                targets[name].append(y)
    fitted = {}
    for name in CHANNELS:
        phi, y = np.array(rows[name]), np.array(targets[name])
        theta0, *_ = np.linalg.lstsq(phi, y, rcond=None)
        p0 = (1.0 - forgetting_factor) * np.linalg.inv(phi.T @ phi / len(y))
        fitted[name] = (theta0, p0)
    return fitted


def calibrate(flights: list[tuple[np.ndarray, np.ndarray, np.ndarray]], sample_period_s: float,
              forgetting_factor: float, window: int, settle_s: float) -> Calibration:
    """The calibration from fault-free flights (times (K,), states (K, n), controls (K, m)
    on the sample grid): the initial parameters, then, from the RLS and GLRT run over each
    flight from them, the parameters' spread and the Weibull fits of both statistics."""
    initial = fit_initial_parameters([(s, c) for _, s, c in flights], forgetting_factor)
    # The RLS and the GLRT need only theta0 and P0; spread and Weibulls are placeholders.
    provisional = Calibration(sample_period_s, forgetting_factor, window, settle_s, {
        name: ChannelCalibration(theta0, p0, np.zeros(theta0.size), np.ones(theta0.size),
                                 Weibull(1.0, 1.0))
        for name, (theta0, p0) in initial.items()}, Weibull(1.0, 1.0))
    samples = [sample for flight in flights
               for sample in run_detector(provisional, flight, false_alarm_probability=0.5)
               if np.isfinite(sample.statistic).all()]
    statistics = np.array([sample.statistic for sample in samples])
    channels, deviation = {}, np.zeros(len(samples))
    for k, name in enumerate(CHANNELS):
        theta = np.array([sample.theta[name] for sample in samples])
        channel = ChannelCalibration(*initial[name], theta.mean(axis=0), theta.std(axis=0),
                                     weibull_fit(statistics[:, k]))
        deviation = np.maximum(deviation, parameter_deviation(theta, channel))
        channels[name] = channel
    return Calibration(sample_period_s, forgetting_factor, window, settle_s, channels,
                       weibull_fit(deviation))


def run_detector(calibration: Calibration, flight: tuple[np.ndarray, np.ndarray, np.ndarray],
                 false_alarm_probability: float) -> list[DetectorSample]:
    """The detector over one flight (times (K,) [s], states (K, n), controls (K, m)) from
    its calibration: every sample it makes."""
    detector = SelfTuningDetector(calibration, false_alarm_probability)
    samples = []
    for time_s, state, control in zip(*flight, strict=True):
        sample = detector.update(time_s, state, control)
        if sample is not None:
            samples.append(sample)
    return samples
