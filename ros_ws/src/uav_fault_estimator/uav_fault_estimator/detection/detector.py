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

The calibration it runs on: calibration.py. No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_common.sample_grid import on_grid

from uav_fault_estimator.detection.calibration import CHANNELS, Calibration, parameter_deviation
from uav_fault_estimator.detection.change_detection import (
    SlidingGlrt,
    weibull_threshold,
)
from uav_fault_estimator.detection.rls import RecursiveLeastSquares

_P, _Q, YAW_RATE = (STATE_CHANNELS.index(name) for name in ("roll_rate", "pitch_rate", "yaw_rate"))
_AILERON, _ELEVATOR = (CONTROL_CHANNELS.index(name) for name in ("aileron", "elevator"))

class DetectorFlight(NamedTuple):
    """One flight on the detector's grid: times_s (K,) [s], states (K, 14) and controls
    (K, 7) in uav_common.channels order, airspeed_mps (K,) [m/s] (NaN where unknown; only an
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
        "yaw": (np.array([aileron, previous_yaw_rate, 1.0]), state[YAW_RATE]),
    }



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
        """One sample (state and controls arrays, uav_common.channels order; the airspeed
        [m/s], which only an airspeed schedule uses: without one known yet, no parameter
        test). None off the grid, for the first sample (the yaw model needs r[k-1]), and for
        a sample with a non-finite value it needs (skipped: the RLS keeps its parameters)."""
        if not on_grid(time_s, self.calibration.sample_period_s):
            return None
        rates = state[[_P, _Q, YAW_RATE]]
        surfaces = controls[[_AILERON, _ELEVATOR]]
        if not (np.all(np.isfinite(rates)) and np.all(np.isfinite(surfaces))):
            self.skipped_samples += 1
            self.previous_yaw_rate = None  # r[k-1] of the next sample is not known either
            return None
        previous, self.previous_yaw_rate = self.previous_yaw_rate, float(state[YAW_RATE])
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
