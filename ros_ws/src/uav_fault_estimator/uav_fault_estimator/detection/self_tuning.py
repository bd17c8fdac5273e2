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
III.D) is raised when some channel's GLRT and parameter tests agree.

Airspeed schedule (the paper's a_pa(U), a_qe(U), a_ra(U), b_ra(U), "air speed U being the
dominating parameter"): a calibration made from flights at several speeds may make the
parameters' fault-free means affine in airspeed, mean_i(U) = mean_i + slope_i (U - U_ref),
U the airspeed filtered with the RLS's own forgetting factor (the parameters' memory), so
that a slow aircraft is not taken for a broken one. The RLS and the GLRT are unchanged: the
RLS tracks the parameters, the GLRT's statistic is scale-free. Why this form and not gains
normalised by U or U^2 (tried, measured): README, "Your own flights". No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

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
DEFAULT_SAMPLE_PERIOD_S = 0.2  # the paper's 5 Hz: the grid of every calibration made here
DEFAULT_SETTLE_S = 30.0  # no test until the RLS has had this long after a start [s]
# The airframe of the shipped calibration: the simulated Aerosonde
# (config/airframes/aerosonde_sim.yaml); a calibration holds for its airframe only.
SIMULATED_AIRFRAME = "aerosonde_sim"
# Least spread of the calibration flights' airspeeds (5th to 95th percentile) for an airspeed
# schedule: over less, the slopes are not told from the noise.
MIN_SCHEDULE_SPAN_MPS = 2.0


class DetectorFlight(NamedTuple):
    """One flight on the detector's grid: times_s (K,) [s], states (K, 14) and controls
    (K, 7) in uav_sim.channels order, airspeed_mps (K,) [m/s] (NaN where unknown; only an
    airspeed schedule needs it)."""

    times_s: np.ndarray
    states: np.ndarray
    controls: np.ndarray
    airspeed_mps: np.ndarray


def detector_flight(flight: Sequence[np.ndarray]) -> DetectorFlight:
    """flight as a DetectorFlight: (times, states, controls) gets an unknown airspeed."""
    if isinstance(flight, DetectorFlight):
        return flight
    times_s, states, controls = flight[:3]
    return DetectorFlight(times_s, states, controls, np.full(len(times_s), math.nan))


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
    covariance P0 of the RLS, the parameters' mean (at the reference airspeed when
    scheduled) and standard deviation in flight, the Weibull distribution of its GLRT
    statistic, and with an airspeed schedule the means' slopes [per m/s]."""

    theta0: np.ndarray
    p0: np.ndarray
    parameter_mean: np.ndarray
    parameter_std: np.ndarray
    glrt: Weibull
    parameter_slope: np.ndarray | None = None

    def expected_parameters(self, airspeed_offset_mps: float) -> np.ndarray:
        """The fault-free mean of the parameters at U_ref + airspeed_offset_mps."""
        if self.parameter_slope is None:
            return self.parameter_mean
        return self.parameter_mean + self.parameter_slope * airspeed_offset_mps


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
    airframe: str = SIMULATED_AIRFRAME
    reference_airspeed_mps: float | None = None  # U_ref of the airspeed schedule; None: none

    @property
    def scheduled(self) -> bool:
        return self.reference_airspeed_mps is not None

    def to_dict(self) -> dict[str, Any]:
        return {
            "airframe": self.airframe,
            "reference_airspeed_mps": self.reference_airspeed_mps,
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
                "parameter_slope_per_mps": (None if c.parameter_slope is None
                                            else c.parameter_slope.tolist()),
                "glrt_weibull": _weibull_dict(c.glrt),
            } for name, c in self.channels.items()},
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Calibration:
        """From to_dict()'s layout; KeyError or ValueError on a malformed one."""
        reference = data["reference_airspeed_mps"]
        channels = {}
        for name in CHANNELS:
            c = data["channels"][name]
            n = len(PARAMETER_NAMES[name])
            arrays = [np.array(c[key], dtype=float) for key in
                      ("theta0", "p0", "parameter_mean", "parameter_std")]
            slope = c["parameter_slope_per_mps"]
            if [a.shape for a in arrays] != [(n,), (n, n), (n,), (n,)] or (
                    (slope is None) != (reference is None)) or (
                    slope is not None and len(slope) != n):
                raise ValueError(f"channel {name}: arrays must be {n}, {n}x{n}, {n}, {n}, and "
                                 f"a slope of {n} exactly when scheduled on airspeed")
            channels[name] = ChannelCalibration(
                *arrays, glrt=Weibull(**c["glrt_weibull"]),
                parameter_slope=None if slope is None else np.array(slope, dtype=float))
        return cls(float(data["sample_period_s"]), float(data["forgetting_factor"]),
                   int(data["window"]), float(data["settle_s"]), channels,
                   Weibull(**data["parameter_deviation_weibull"]), str(data["airframe"]),
                   None if reference is None else float(reference))


def _weibull_dict(distribution: Weibull) -> dict[str, float]:
    return {"scale": distribution.scale, "shape": distribution.shape}


def parameter_deviation(theta: np.ndarray, channel: ChannelCalibration,
                        airspeed_offset_mps: float | np.ndarray = 0.0) -> np.ndarray:
    """The largest |theta_i - mean_i(U)| / std_i over a channel's parameters (section
    III.C); theta (n,) or (K, n) for K samples, airspeed_offset_mps U - U_ref [m/s] (scalar
    or (K,); unused without a schedule)."""
    offset = np.asarray(airspeed_offset_mps, dtype=float)[..., None]
    return np.max(np.abs(theta - channel.expected_parameters(offset)) / channel.parameter_std,
                  axis=-1)


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
    airspeed_mps: float  # the filtered airspeed the schedule used (NaN: none known)


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
        self.filtered_airspeed_mps = math.nan

    def filter_airspeed(self, airspeed_mps: float) -> float:
        """The airspeed through the RLS's forgetting (the memory its parameters have); the
        first known value starts it, an unknown one leaves it [m/s]."""
        if math.isfinite(airspeed_mps):
            previous = self.filtered_airspeed_mps
            forgetting = self.calibration.forgetting_factor
            self.filtered_airspeed_mps = (airspeed_mps if math.isnan(previous) else
                                          forgetting * previous
                                          + (1.0 - forgetting) * airspeed_mps)
        return self.filtered_airspeed_mps

    def update(self, time_s: float, state: np.ndarray, controls: np.ndarray,
               airspeed_mps: float = math.nan) -> DetectorSample | None:
        """One sample (state and controls arrays, uav_sim.channels order; the airspeed
        [m/s], which only an airspeed schedule uses: without one known yet, no parameter
        test). None off the grid, for the first sample (the yaw model needs r[k-1]), and for
        a sample with a non-finite value it needs (skipped: the RLS keeps its parameters)."""
        if not on_grid(time_s, self.calibration.sample_period_s):
            return None
        rates = state[[_P, _Q, _R]]
        surfaces = controls[[_AILERON, _ELEVATOR]]
        if not (np.all(np.isfinite(rates)) and np.all(np.isfinite(surfaces))):
            self.skipped_samples += 1
            self.previous_yaw_rate = None  # r[k-1] of the next sample is not known either
            return None
        previous, self.previous_yaw_rate = self.previous_yaw_rate, float(state[_R])
        if previous is None:  # the first sample, or the first after a gap
            if self.started_s is None:
                self.started_s = time_s
            self.skipped_samples += 1
            return None
        airspeed_offset_mps = self.airspeed_offset_mps(airspeed_mps)
        settled = time_s - self.started_s >= self.calibration.settle_s
        regression = regressions(state, controls, previous)
        residual, statistic, deviation, theta = [], [], [], {}
        for name in CHANNELS:
            step = self.rls[name].update(*regression[name])
            channel = self.calibration.channels[name]
            g = self.glrt[name].update(step.prediction_error)
            residual.append(step.prediction_error)
            statistic.append(g if g is not None and settled else math.nan)
            deviation.append(float(parameter_deviation(step.theta, channel, airspeed_offset_mps))
                             if settled else math.nan)  # NaN offset: NaN, no alarm
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
            airspeed_mps=self.filtered_airspeed_mps,
        )

    def airspeed_offset_mps(self, airspeed_mps: float) -> float:
        """U - U_ref of the schedule from this sample's airspeed [m/s] (filter_airspeed);
        0 without a schedule, NaN while no airspeed is known."""
        filtered = self.filter_airspeed(airspeed_mps)
        reference = self.calibration.reference_airspeed_mps
        return 0.0 if reference is None else filtered - reference


def shipped_calibration_path() -> Path:
    """The package's config/detector_calibration.yaml (scripts/calibrate_detector.py)."""
    return config_path("uav_fault_estimator", "detector_calibration.yaml")


def load_calibration(path: str, window: int, forgetting_factor: float,
                     airframe: str = SIMULATED_AIRFRAME) -> Calibration:
    """The calibration file (empty path: the shipped one), checked against the node's
    window and forgetting factor and the airframe flown; ValueError with one line naming
    the file."""
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
    if calibration.airframe != airframe:
        raise ValueError(
            f"calibration file {file} is for the airframe '{calibration.airframe}', not "
            f"'{airframe}': calibrate from fault-free flights of '{airframe}' "
            "(scripts/screen_logs.py)")
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


def calibrate(flights: Sequence[Sequence[np.ndarray]], sample_period_s: float,
              forgetting_factor: float, window: int, settle_s: float,
              airframe: str = SIMULATED_AIRFRAME, scheduled: bool = False) -> Calibration:
    """The calibration of airframe from fault-free flights on the sample grid
    (DetectorFlight, or (times, states, controls) without airspeed): the initial
    parameters, then, from the RLS and GLRT run over each flight from them, the parameters'
    spread and the Weibull fits of both statistics. scheduled: the parameters' means affine
    in the filtered airspeed (airspeed_schedule); ValueError when the flights' airspeeds
    span less than MIN_SCHEDULE_SPAN_MPS."""
    flights = [detector_flight(flight) for flight in flights]
    initial = fit_initial_parameters([(f.states, f.controls) for f in flights],
                                     forgetting_factor)
    # The RLS and the GLRT need only theta0 and P0; spread and Weibulls are placeholders.
    provisional = Calibration(sample_period_s, forgetting_factor, window, settle_s, {
        name: ChannelCalibration(theta0, p0, np.zeros(theta0.size), np.ones(theta0.size),
                                 Weibull(1.0, 1.0))
        for name, (theta0, p0) in initial.items()}, Weibull(1.0, 1.0), airframe)
    samples = [sample for flight in flights
               for sample in run_detector(provisional, flight, false_alarm_probability=0.5)
               if np.isfinite(sample.statistic).all()]
    statistics = np.array([sample.statistic for sample in samples])
    airspeeds = np.array([sample.airspeed_mps for sample in samples])
    reference = airspeed_reference(airspeeds) if scheduled else None
    channels, deviation = {}, np.zeros(len(samples))
    for k, name in enumerate(CHANNELS):
        theta = np.array([sample.theta[name] for sample in samples])
        mean, slope, std = (airspeed_schedule(theta, airspeeds - reference) if scheduled
                            else (theta.mean(axis=0), None, theta.std(axis=0)))
        channel = ChannelCalibration(*initial[name], mean, std, weibull_fit(statistics[:, k]),
                                     slope)
        offsets = airspeeds - reference if scheduled else 0.0
        deviation = np.maximum(deviation, parameter_deviation(theta, channel, offsets))
        channels[name] = channel
    return Calibration(sample_period_s, forgetting_factor, window, settle_s, channels,
                       weibull_fit(deviation), airframe, reference)


def airspeed_reference(airspeeds_mps: np.ndarray) -> float:
    """U_ref of a schedule: the calibration samples' median airspeed [m/s]; ValueError when
    they have none or span less than MIN_SCHEDULE_SPAN_MPS (5th to 95th percentile)."""
    known = airspeeds_mps[np.isfinite(airspeeds_mps)]
    if known.size < airspeeds_mps.size or known.size == 0:
        raise ValueError("an airspeed schedule needs the airspeed of every calibration "
                         f"sample; {airspeeds_mps.size - known.size} of {airspeeds_mps.size} "
                         "have none")
    low, high = np.percentile(known, [5.0, 95.0])
    if high - low < MIN_SCHEDULE_SPAN_MPS:
        raise ValueError(f"the calibration flights span {low:.1f}-{high:.1f} m/s of airspeed: "
                         f"an airspeed schedule needs at least {MIN_SCHEDULE_SPAN_MPS:g} m/s "
                         "(fly them at several speeds, or calibrate without a schedule)")
    return float(np.median(known))


def airspeed_schedule(theta: np.ndarray, airspeed_offsets_mps: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The parameters' fault-free mean at U_ref, slope [per m/s] and standard deviation
    about that line: least squares of theta (K, n) on (1, U - U_ref) over the samples."""
    regressors = np.column_stack([np.ones_like(airspeed_offsets_mps), airspeed_offsets_mps])
    (mean, slope), *_ = np.linalg.lstsq(regressors, theta, rcond=None)
    return mean, slope, (theta - regressors @ np.vstack([mean, slope])).std(axis=0)


def run_detector(calibration: Calibration, flight: Sequence[np.ndarray],
                 false_alarm_probability: float) -> list[DetectorSample]:
    """The detector over one flight (DetectorFlight, or (times, states, controls) without
    airspeed) from its calibration: every sample it makes."""
    detector = SelfTuningDetector(calibration, false_alarm_probability)
    samples = []
    for time_s, state, control, airspeed_mps in zip(*detector_flight(flight), strict=True):
        sample = detector.update(time_s, state, control, airspeed_mps)
        if sample is not None:
            samples.append(sample)
    return samples
