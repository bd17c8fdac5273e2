"""The detector's calibration from fault-free flights (Blanke & Hansen, section III): the
RLS's initial parameters by least squares, then, from the detector run over each flight,
the parameters' spread (optionally scheduled on airspeed) and the Weibull fits of both
statistics; and the fast test's: the spread of each generator's residual with theta0
fixed, and the Weibull fit of its window statistic. No ROS here."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from uav_fault_estimator.detection.calibration import (
    DEFAULT_FAST_REFERENCE,
    DEFAULT_FAST_WINDOW,
    DEFAULT_FORGETTING_FACTOR,
    DEFAULT_SAMPLE_PERIOD_S,
    DEFAULT_SETTLE_S,
    DEFAULT_WINDOW,
    MIN_SCHEDULE_SPAN_MPS,
    SIMULATED_AIRFRAME,
    Calibration,
    ChannelCalibration,
    FastTestCalibration,
    parameter_deviation,
)
from uav_fault_estimator.detection.change_detection import (
    SlidingMeanChange,
    Weibull,
    weibull_fit,
)
from uav_fault_estimator.detection.detector import (
    DetectorFlight,
    DetectorSample,
    detector_flight,
    flight_regressions,
    run_detector,
)
from uav_fault_estimator.detection.generators import SURFACE_GENERATORS, checked_generators


def fit_initial_parameters(flights: Iterable[DetectorFlight], generators: tuple[str, ...],
                           sample_period_s: float, forgetting_factor: float
                           ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """theta0 and P0 per generator from flights on the sample grid: theta0 the least-squares
    fit over every sample the detector would use, P0 the RLS covariance it settles to on
    such data, (1 - lambda_f) (Phiᵀ Phi / K)^-1."""
    rows: dict[str, list] = {name: [] for name in generators}
    targets: dict[str, list] = {name: [] for name in generators}
    for flight in flights:
        for regression in flight_regressions(flight, generators, sample_period_s):
            for name, (phi, y) in regression.items():
                rows[name].append(phi)
                targets[name].append(y)
    fitted = {}
    for name in generators:
        phi, y = np.array(rows[name]), np.array(targets[name])
        if phi.ndim != 2 or len(y) <= phi.shape[1]:
            raise ValueError(f"generator {name}: {len(y)} usable fault-free samples, too few "
                             "to fit it (does every flight carry what it takes?)")
        theta0, *_ = np.linalg.lstsq(phi, y, rcond=None)
        p0 = (1.0 - forgetting_factor) * np.linalg.inv(phi.T @ phi / len(y))
        fitted[name] = (theta0, p0)
    return fitted


def calibrate(flights: Sequence[Sequence[np.ndarray]],
              sample_period_s: float = DEFAULT_SAMPLE_PERIOD_S,
              forgetting_factor: float = DEFAULT_FORGETTING_FACTOR,
              window: int = DEFAULT_WINDOW, settle_s: float = DEFAULT_SETTLE_S,
              airframe: str = SIMULATED_AIRFRAME, scheduled: bool = False,
              generators: tuple[str, ...] = SURFACE_GENERATORS,
              fast_window: int = DEFAULT_FAST_WINDOW,
              fast_reference: int = DEFAULT_FAST_REFERENCE) -> Calibration:
    """The calibration of airframe's generators (generators.GENERATORS) from fault-free
    flights on the sample grid (DetectorFlight, or (times, states, controls) without
    airspeed), made with (and carrying) the sample period [s], forgetting factor, GLRT
    window [samples], settling time [s] and fast-test window and reference [samples]: the
    initial parameters, then, from the RLS and GLRT run over each flight from them, the
    parameters' spread, the Weibull fits of both statistics and the fast test's
    (fast_calibration). scheduled: the parameters' means affine in the filtered airspeed
    (airspeed_schedule); ScheduleError when the flights' airspeeds span less than
    MIN_SCHEDULE_SPAN_MPS, ValueError when a generator has too few samples."""
    generators = checked_generators(tuple(generators))
    flights = [detector_flight(flight) for flight in flights]
    initial = fit_initial_parameters(flights, generators, sample_period_s, forgetting_factor)
    # The RLS and the GLRT need only theta0 and P0; spread and Weibulls are placeholders.
    placeholder = FastTestCalibration(1.0, Weibull(1.0, 1.0))
    provisional = Calibration(sample_period_s, forgetting_factor, window, settle_s, {
        name: ChannelCalibration(theta0, p0, np.zeros(theta0.size), np.ones(theta0.size),
                                 Weibull(1.0, 1.0), placeholder)
        for name, (theta0, p0) in initial.items()}, Weibull(1.0, 1.0), airframe,
        fast_window=fast_window, fast_reference=fast_reference)
    runs = [run_detector(provisional, flight, false_alarm_probability=0.5) for flight in flights]
    samples = [sample for run in runs for sample in run if np.isfinite(sample.statistic).all()]
    fast = fast_calibration(runs, fast_window, fast_reference)
    statistics = np.array([sample.statistic for sample in samples])
    airspeeds = np.array([sample.airspeed_mps for sample in samples])
    reference = airspeed_reference(airspeeds) if scheduled else None
    channels, deviation = {}, np.zeros(len(samples))
    for k, name in enumerate(generators):
        theta = np.array([sample.theta[name] for sample in samples])
        mean, slope, std = (airspeed_schedule(theta, airspeeds - reference) if scheduled
                            else (theta.mean(axis=0), None, theta.std(axis=0)))
        channel = ChannelCalibration(*initial[name], mean, std, weibull_fit(statistics[:, k]),
                                     fast[k], slope)
        offsets = airspeeds - reference if scheduled else 0.0
        deviation = np.maximum(deviation, parameter_deviation(theta, channel, offsets))
        channels[name] = channel
    return Calibration(sample_period_s, forgetting_factor, window, settle_s, channels,
                       weibull_fit(deviation), airframe, reference, fast_window, fast_reference)


def fast_calibration(runs: Sequence[Sequence[DetectorSample]], window: int, reference: int
                     ) -> list[FastTestCalibration]:
    """Per generator, from every sample of each fault-free flight's detector run (the
    fixed-parameter residual needs no settling): the standard deviation of the residual with
    theta0 fixed over every flight, and the Weibull fit of its window statistic (`window`
    samples against the `reference` before them), each flight's windows its own. ValueError
    when the flights give fewer than ten statistics (the Weibull fit's least)."""
    residuals = [np.array([sample.fixed_residual for sample in run]) for run in runs if run]
    statistics_count = sum(max(0, len(flight) - window - reference + 1) for flight in residuals)
    if statistics_count < 10:
        raise ValueError(f"the fast test needs ten windows of {window} samples after a "
                         f"reference of {reference}: the flights give {statistics_count} "
                         f"(their usable samples: {', '.join(map(str, map(len, residuals)))})")
    stds = np.vstack(residuals).std(axis=0)
    fitted = []
    for k, std in enumerate(stds):
        statistics = []
        for flight in residuals:
            test = SlidingMeanChange(window, reference, float(std))
            statistics += [abs(z) for z in map(test.update, flight[:, k]) if z is not None]
        fitted.append(FastTestCalibration(float(std), weibull_fit(np.array(statistics))))
    return fitted


class ScheduleError(ValueError):
    """Calibration flights that cannot give an airspeed schedule (one line: why)."""


# How a calibration command schedules: on airspeed where the flights allow it (auto), on
# airspeed or not at all (airspeed: refused otherwise), never (none).
SCHEDULES = ("auto", "airspeed", "none")


def calibrate_scheduled(flights: Sequence[Sequence[np.ndarray]], schedule: str,
                        **settings: Any) -> tuple[Calibration, str | None]:
    """calibrate(flights, **settings) scheduled as `schedule` (SCHEDULES) says; and, when auto
    found no schedule, why (None otherwise). ScheduleError when `airspeed` cannot be had."""
    if schedule not in SCHEDULES:
        raise ValueError(f"schedule {schedule!r}: expected one of {', '.join(SCHEDULES)}")
    if schedule != "none":
        try:
            return calibrate(flights, scheduled=True, **settings), None
        except ScheduleError as error:
            if schedule == "airspeed":
                raise
            return calibrate(flights, scheduled=False, **settings), str(error)
    return calibrate(flights, scheduled=False, **settings), None


def airspeed_reference(airspeeds_mps: np.ndarray) -> float:
    """U_ref of a schedule: the calibration samples' median airspeed [m/s]; ScheduleError
    when they have none or span less than MIN_SCHEDULE_SPAN_MPS (5th to 95th percentile)."""
    known = airspeeds_mps[np.isfinite(airspeeds_mps)]
    if known.size < airspeeds_mps.size or known.size == 0:
        raise ScheduleError("an airspeed schedule needs the airspeed of every calibration "
                         f"sample; {airspeeds_mps.size - known.size} of {airspeeds_mps.size} "
                         "have none")
    low, high = np.percentile(known, [5.0, 95.0])
    if high - low < MIN_SCHEDULE_SPAN_MPS:
        raise ScheduleError(f"the calibration flights span {low:.1f}-{high:.1f} m/s of airspeed: "
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


