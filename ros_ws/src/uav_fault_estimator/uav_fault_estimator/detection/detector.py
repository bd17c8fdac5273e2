"""The self-tuning detector and its combined alarm (Blanke & Hansen).

Residual generators (generators.py), each identified in flight by recursive least squares
(rls.py) from parameters learned on earlier fault-free flights (the calibration, which names
the generators it holds). Per generator (the detector's channel), on every sample of the
grid (sample_period_s, the paper's 5 Hz): the residual is the RLS prediction error (eq. 9),
its GLRT statistic over the last M samples (change_detection.py, eq. 22) against the
threshold for the designed false-alarm probability (eq. 25, Weibull of the statistic on
fault-free flights), and the parameter deviation: the largest |theta_i - mean_i| / std_i
against the fault-free spread (section III.C), whose threshold comes from a Weibull fit of
the same statistic on the same flights, for the same P_FA. The paper's combined alarm
(section III.D) is raised when some channel's GLRT and parameter tests agree.

Beside it, the fast test: per generator, the residual with the parameters the calibration
fixed (theta0), y - phiᵀ theta0, the change of its mean over the last W samples from the R
before them (change_detection.SlidingMeanChange) against the threshold for a stated rate of
false alarms per flight hour (Weibull of the statistic on the same fault-free flights).
The self-tuning RLS absorbs a change within seconds, before its GLRT window confirms it;
the fixed parameters absorb nothing, and a constant offset (a new day's trim or sensor
bias) moves both windows alike. The combined alarm takes either test (docs/detector.md:
confirming the fast test by the GLRT kept ALFA's new days as quiet but cost it most of its
speed in simulation).

With templates (templates.py, learned with the signatures), the template test too: each
failure's learned shape over the generators, slid over the fixed-parameter residuals
whitened by their fault-free colour, against the threshold for a stated rate of false
alarms per flight hour; the combined alarm takes it as well.

The calibration it runs on: calibration.py. No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from uav_common.sample_grid import on_grid

from uav_fault_estimator.detection.calibration import Calibration, parameter_deviations
from uav_fault_estimator.detection.change_detection import (
    SlidingGlrt,
    SlidingMeanChange,
    per_sample_probability,
    weibull_threshold,
)
from uav_fault_estimator.detection.generators import (
    KIND_OF_GENERATOR,
    NO_SETPOINTS,
    SETPOINTS,
    GridSample,
    Regression,
    regressions,
)
from uav_fault_estimator.detection.rls import RecursiveLeastSquares
from uav_fault_estimator.detection.signatures import (
    FailureSignatures,
    signature_features,
    signature_of,
)
from uav_fault_estimator.detection.templates import (
    DEFAULT_TEMPLATE_FALSE_ALARMS_PER_HOUR,
    FailureTemplates,
    TemplateTest,
)

# The fast test's designed false alarms per flight hour, each channel. Chosen on ALFA's
# flights leaving a day out (docs/detector.md): at 1 and 0.1 per hour a new day's
# fault-free stretches raised it on 7 and 2 flights, at 0.01 on none; on the simulated dev
# flights 0.01 found about as many failures within 5 s as 1.
DEFAULT_FAST_FALSE_ALARMS_PER_HOUR = 0.01


class DetectorFlight(NamedTuple):
    """One flight on the detector's grid: times_s (K,) [s], states (K, 14) and controls
    (K, 7) in uav_common.channels order, airspeed_mps (K,) [m/s] (NaN where unknown; only an
    airspeed schedule needs it), setpoints (K, 3) the autopilot's in generators.SETPOINTS
    order (None or NaN where unknown)."""

    times_s: np.ndarray
    states: np.ndarray
    controls: np.ndarray
    airspeed_mps: np.ndarray
    setpoints: np.ndarray | None = None


def detector_flight(flight: Sequence[np.ndarray]) -> DetectorFlight:
    """flight as a DetectorFlight: (times, states, controls) gets an unknown airspeed."""
    if isinstance(flight, DetectorFlight):
        return flight
    times_s, states, controls = flight[:3]
    return DetectorFlight(times_s, states, controls, np.full(len(times_s), math.nan))


@dataclass(frozen=True)
class DetectorSample:
    """One detector step: per channel (the calibration's order) residual, GLRT statistic
    (NaN while the window fills or the RLS settles), threshold, alarm and parameter
    deviation (the largest of its parameters'); each parameter's signed deviation, channel
    after channel (NaN while the RLS settles); the parameter threshold and alarm; per
    channel the fast test's residual (parameters fixed), signed change (NaN while its
    window fills or the RLS settles; its size the statistic), threshold and alarm; the
    combined alarm (any test); each channel's parameters; the cause the combined alarm
    names (empty without one): the failure its signature (fast-test changes and parameter
    deviations) resembles most (signatures.FailureSignatures) where the detector has
    signatures, else an alarming template's (the one furthest over its threshold), else the
    kind of the channel whose alarming test lies furthest over its threshold
    (generators.FAILURE_GENERATORS); and per template (none without templates)
    its statistic (NaN while its window fills or the RLS settles), threshold and alarm."""

    time_s: float
    residual: np.ndarray
    statistic: np.ndarray
    threshold: np.ndarray
    alarm: np.ndarray
    parameter_deviation: np.ndarray
    parameter_deviations: np.ndarray
    parameter_threshold: float
    parameter_alarm: bool
    fixed_residual: np.ndarray
    fast_change: np.ndarray
    fast_threshold: np.ndarray
    fast_alarm: np.ndarray
    combined_alarm: bool
    theta: dict[str, np.ndarray]
    airspeed_mps: float  # the filtered airspeed the schedule used (NaN: none known)
    cause: str = ""
    template_statistic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    template_threshold: np.ndarray = field(default_factory=lambda: np.zeros(0))
    template_alarm: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    @property
    def fast_statistic(self) -> np.ndarray:
        """Each channel's fast-test statistic: the size of its change (NaN where none)."""
        return np.abs(self.fast_change)

    @property
    def self_tuning_alarm(self) -> bool:
        """The paper's combined alarm: some channel's GLRT and parameter tests agree."""
        return bool(np.any(self.alarm & (self.parameter_deviation > self.parameter_threshold)))

    @property
    def channel_combined_alarm(self) -> np.ndarray:
        """Per channel, the combined alarm's rule (channel_combined_alarm below)."""
        return channel_combined_alarm(self.alarm, self.parameter_deviation
                                      > self.parameter_threshold, self.fast_alarm)

    @property
    def signature(self) -> np.ndarray:
        """The sample's failure signature (signatures.signature_of)."""
        return signature_of(self.fast_change, self.parameter_deviations)


def channel_combined_alarm(alarm: np.ndarray, deviates: np.ndarray, fast_alarm: np.ndarray
                           ) -> np.ndarray:
    """Per channel, the combined alarm: its GLRT and parameter tests agree (section III.D),
    or its fast test alarms; the detector's combined alarm is raised when some channel's is."""
    return (alarm & deviates) | fast_alarm


def fixed_residuals(samples: Sequence[DetectorSample]) -> tuple[np.ndarray, np.ndarray]:
    """times (K,) [s] of a detector run's samples, and their residuals with the
    calibration's parameters fixed, y - phiᵀ theta0 (K, G), generators in the calibration's
    order."""
    return (np.array([sample.time_s for sample in samples]),
            np.array([sample.fixed_residual for sample in samples]))


def first_combined_alarm(samples: Sequence[DetectorSample], after_s: float = -math.inf
                         ) -> DetectorSample | None:
    """The first sample at or after after_s [s] with a combined alarm; None without one."""
    return next((sample for sample in samples
                 if sample.combined_alarm and sample.time_s >= after_s), None)


class RegressionFeed:
    """The samples of a flight as the generators' regressions, on the grid of period_s [s]:
    which samples can be used, and each one's sample before."""

    def __init__(self, generators: tuple[str, ...], period_s: float) -> None:
        self.generators = generators
        self.period_s = period_s
        self.skipped_samples = 0  # samples on the grid that could not be used
        self.restart()

    def restart(self) -> None:
        """From a start: no sample before, not started; the count of skipped samples kept."""
        self.previous: GridSample | None = None
        self.started_s: float | None = None  # the first usable sample's time [s]

    def step(self, time_s: float, state: np.ndarray, controls: np.ndarray,
             setpoints: np.ndarray) -> dict[str, Regression] | None:
        """Each generator's (phi, y) for this sample; None off the grid, for the first
        sample when a generator needs the sample before, and for a sample with a non-finite
        value a generator takes (then the next sample has no sample before)."""
        if not on_grid(time_s, self.period_s):
            return None
        now = GridSample(time_s, state, controls, setpoints)
        regression = regressions(self.generators, now, self.previous)
        if regression is None:
            self.skipped_samples += 1
            # Only the sample before is missing when, given itself one period earlier as the
            # one before, this sample is complete: it is then the next sample's sample before.
            itself_before = now._replace(time_s=time_s - self.period_s)
            first = (self.previous is None
                     and regressions(self.generators, now, itself_before) is not None)
            self.previous = now if first else None
        else:
            self.previous = now
        if self.previous is not None and self.started_s is None:
            self.started_s = time_s
        return regression


def flight_regressions(flight: Sequence[np.ndarray], generators: tuple[str, ...],
                       period_s: float) -> Iterator[dict[str, Regression]]:
    """Every usable sample's regressions over one flight (DetectorFlight, or (times, states,
    controls) without airspeed), as the detector forms them."""
    feed = RegressionFeed(generators, period_s)
    for time_s, state, controls, _, setpoints in flight_samples(flight):
        regression = feed.step(time_s, state, controls, setpoints)
        if regression is not None:
            yield regression


def flight_samples(flight: Sequence[np.ndarray]) -> Iterator[tuple]:
    """(time_s, state, controls, airspeed_mps, setpoints) of each sample of a flight."""
    flight = detector_flight(flight)
    setpoints = (np.full((len(flight.times_s), len(SETPOINTS)), math.nan)
                 if flight.setpoints is None else flight.setpoints)
    yield from zip(*flight[:4], setpoints, strict=True)


class SelfTuningDetector:
    """Feed it every sample; it acts on the calibration's sample grid, with the generators
    the calibration names; its alarms name their cause by the signatures (learned with the
    calibration: signatures.signature_features; None: by the strongest channel); with
    templates (learned with the calibration's generators) it runs the template test too."""

    def __init__(self, calibration: Calibration, false_alarm_probability: float,
                 fast_false_alarms_per_hour: float = DEFAULT_FAST_FALSE_ALARMS_PER_HOUR,
                 signatures: FailureSignatures | None = None,
                 templates: FailureTemplates | None = None,
                 template_false_alarms_per_hour: float = DEFAULT_TEMPLATE_FALSE_ALARMS_PER_HOUR
                 ) -> None:
        if signatures is not None and signatures.features != signature_features(calibration):
            raise ValueError(f"signatures over {', '.join(signatures.features)}: the "
                             "calibration's are over "
                             f"{', '.join(signature_features(calibration))}")
        if templates is not None and len(templates.spread) != len(calibration.channels):
            raise ValueError(f"templates over {len(templates.spread)} generators: the "
                             f"calibration has {len(calibration.channels)}")
        self.calibration = calibration
        self.signatures = signatures
        self.templates = templates
        self.set_false_alarm_probability(false_alarm_probability)
        self.set_fast_false_alarm_rate(fast_false_alarms_per_hour)
        self.set_template_false_alarm_rate(template_false_alarms_per_hour)
        self.feed = RegressionFeed(calibration.channel_names, calibration.sample_period_s)
        self.reset()

    def set_false_alarm_probability(self, false_alarm_probability: float) -> None:
        """The thresholds of every test for this designed false-alarm probability per sample
        (eq. 25), from the next sample on; the generators' state is kept."""
        calibration = self.calibration
        self.false_alarm_probability = false_alarm_probability
        self.thresholds = np.array([weibull_threshold(channel.glrt, false_alarm_probability)
                                    for channel in calibration.channels.values()])
        self.parameter_threshold = weibull_threshold(calibration.parameter,
                                                     false_alarm_probability)

    def set_fast_false_alarm_rate(self, false_alarms_per_hour: float) -> None:
        """The fast test's thresholds for this designed rate of false alarms per flight hour
        (each channel), from the next sample on."""
        c = self.calibration
        probability = per_sample_probability(false_alarms_per_hour, c.fast_window,
                                             c.sample_period_s)
        self.fast_false_alarms_per_hour = false_alarms_per_hour
        self.fast_thresholds = np.array([weibull_threshold(channel.fast.statistic, probability)
                                         for channel in c.channels.values()])

    def set_template_false_alarm_rate(self, false_alarms_per_hour: float) -> None:
        """The template test's thresholds for this designed rate of false alarms per flight
        hour (each template), from the next sample on."""
        self.template_false_alarms_per_hour = false_alarms_per_hour
        self.template_thresholds = (
            np.zeros(0) if self.templates is None else
            self.templates.thresholds(false_alarms_per_hour, self.calibration.sample_period_s))

    def reset(self) -> None:
        """Back to the calibration's parameters: after a restart of the source. The count
        of skipped samples is kept."""
        c = self.calibration
        self.feed.restart()
        self.rls = {name: RecursiveLeastSquares(channel.theta0, channel.p0, c.forgetting_factor)
                    for name, channel in c.channels.items()}
        self.glrt = {name: SlidingGlrt(c.window) for name in c.channels}
        self.fast = {name: SlidingMeanChange(c.fast_window, c.fast_reference,
                                             channel.fast.residual_std)
                     for name, channel in c.channels.items()}
        self.template_test = None if self.templates is None else TemplateTest(self.templates)
        self.filtered_airspeed_mps = math.nan

    @property
    def skipped_samples(self) -> int:
        """Samples on the grid that could not be used, over the detector's life."""
        return self.feed.skipped_samples

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
               airspeed_mps: float = math.nan,
               setpoints: np.ndarray = NO_SETPOINTS) -> DetectorSample | None:
        """One sample (state and controls arrays, uav_common.channels order; the airspeed
        [m/s], which only an airspeed schedule uses: with one and none known yet, no
        parameter test; the autopilot's setpoints (generators.SETPOINTS), which the tracking
        generators take). None off the grid, for the first sample when a generator
        needs the sample before, and for a sample with a non-finite value a generator takes
        (skipped: the RLS keeps its parameters, and the next sample has no sample before)."""
        regression = self.feed.step(time_s, state, controls, setpoints)
        if regression is None:
            return None
        airspeed_offset_mps = self.airspeed_offset_mps(airspeed_mps)
        settled = time_s - self.feed.started_s >= self.calibration.settle_s
        residual, statistic, deviations, theta = [], [], [], {}
        fixed, fast = [], []
        for name, channel in self.calibration.channels.items():
            phi, y = regression[name]
            fixed.append(y - phi @ channel.theta0)
            z = self.fast[name].update(fixed[-1])
            fast.append(z if z is not None and settled else math.nan)
            step = self.rls[name].update(phi, y)
            g = self.glrt[name].update(step.prediction_error)
            residual.append(step.prediction_error)
            statistic.append(g if g is not None and settled else math.nan)
            # NaN offset: NaN, no alarm
            deviations.append(parameter_deviations(step.theta, channel, airspeed_offset_mps)
                              if settled else np.full(len(step.theta), math.nan))
            theta[name] = step.theta
        template = self.template_statistic(np.array(fixed), settled)
        template_alarm = template > self.template_thresholds
        deviation = np.array([np.max(np.abs(d)) for d in deviations])
        statistic, fast = np.array(statistic), np.array(fast)
        signed_deviations = np.concatenate(deviations)
        alarm = statistic > self.thresholds  # NaN compares False
        deviates = deviation > self.parameter_threshold
        fast_alarm = np.abs(fast) > self.fast_thresholds
        combined = bool(channel_combined_alarm(alarm, deviates, fast_alarm).any()
                        or template_alarm.any())
        return DetectorSample(
            time_s=time_s, residual=np.array(residual), statistic=statistic,
            threshold=self.thresholds.copy(), alarm=alarm, parameter_deviation=deviation,
            parameter_deviations=signed_deviations, parameter_threshold=self.parameter_threshold,
            parameter_alarm=bool(deviates.any()), fixed_residual=np.array(fixed),
            fast_change=fast, fast_threshold=self.fast_thresholds.copy(),
            fast_alarm=fast_alarm,
            combined_alarm=combined, theta=theta, airspeed_mps=self.filtered_airspeed_mps,
            cause=self.cause(signature_of(fast, signed_deviations),
                             np.where(alarm & deviates, statistic / self.thresholds, 0.0),
                             np.where(fast_alarm, np.abs(fast) / self.fast_thresholds, 0.0),
                             np.where(template_alarm, template / self.template_thresholds,
                                      0.0))
            if combined else "",
            template_statistic=template, template_threshold=self.template_thresholds.copy(),
            template_alarm=template_alarm,
        )

    def template_statistic(self, fixed_residual: np.ndarray, settled: bool) -> np.ndarray:
        """Each template's statistic for this sample's fixed-parameter residuals (N,): NaN
        while its window fills or the RLS settles; empty without templates."""
        if self.template_test is None:
            return np.zeros(0)
        statistic = self.template_test.update(fixed_residual)
        if statistic is None or not settled:
            return np.full(len(self.template_thresholds), math.nan)
        return statistic

    def cause(self, signature: np.ndarray, self_tuning_ratio: np.ndarray,
              fast_ratio: np.ndarray, template_ratio: np.ndarray) -> str:
        """An alarm's cause: the signatures' for its signature (signatures.signature_of), else
        (no signatures, the signature not yet known) the cause of the alarming template
        furthest over its threshold (ratios of statistic to threshold, 0 where a template
        does not alarm), else alarm_cause's. The signatures come first: a template answers
        to other failures' shapes too (the engine cut's to a stuck elevator's pitch-down),
        and on the dev flights the signatures named more first alarms right (docs/detector.md)."""
        named = "" if self.signatures is None else self.signatures.cause(signature)
        if named:
            return named
        if np.any(template_ratio > 0.0):
            return self.templates.causes[int(np.argmax(template_ratio))]
        return alarm_cause(self.calibration.channel_names, self_tuning_ratio, fast_ratio)

    def airspeed_offset_mps(self, airspeed_mps: float) -> float:
        """U - U_ref of the schedule from this sample's airspeed [m/s] (filter_airspeed);
        0 without a schedule, NaN while no airspeed is known."""
        filtered = self.filter_airspeed(airspeed_mps)
        reference = self.calibration.reference_airspeed_mps
        return 0.0 if reference is None else filtered - reference


def alarm_cause(channel_names: Sequence[str], self_tuning_ratio: np.ndarray,
                fast_ratio: np.ndarray) -> str:
    """The failure kind of the channel whose alarming test lies furthest over its threshold:
    ratios (per channel) of statistic to threshold where the test alarms, 0 elsewhere; empty
    when none alarms, and for a generator of no kind."""
    strength = np.maximum(self_tuning_ratio, fast_ratio)
    if not np.any(strength > 0.0):
        return ""
    return KIND_OF_GENERATOR.get(channel_names[int(np.argmax(strength))], "")


def run_detector(calibration: Calibration, flight: Sequence[np.ndarray],
                 false_alarm_probability: float,
                 fast_false_alarms_per_hour: float = DEFAULT_FAST_FALSE_ALARMS_PER_HOUR,
                 signatures: FailureSignatures | None = None,
                 templates: FailureTemplates | None = None,
                 template_false_alarms_per_hour: float = DEFAULT_TEMPLATE_FALSE_ALARMS_PER_HOUR
                 ) -> list[DetectorSample]:
    """The detector over one flight (DetectorFlight, or (times, states, controls) without
    airspeed) from its calibration (and signatures, templates): every sample it makes."""
    return detector_samples(SelfTuningDetector(
        calibration, false_alarm_probability, fast_false_alarms_per_hour, signatures,
        templates, template_false_alarms_per_hour), flight)


def detector_samples(detector: SelfTuningDetector, flight: Sequence[np.ndarray]
                     ) -> list[DetectorSample]:
    """Every sample the detector makes over one flight (DetectorFlight, or (times, states,
    controls) without airspeed), from its calibration's parameters (reset first)."""
    detector.reset()
    samples = []
    for sample in flight_samples(flight):
        result = detector.update(*sample)
        if result is not None:
            samples.append(result)
    return samples
