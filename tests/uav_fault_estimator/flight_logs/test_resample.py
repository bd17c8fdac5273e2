"""Resampling onto the detector's grid on known signals: a ramp at jittered instants comes
out exact, a step held lands on the right grid points, a gap is NaN there and only there,
nothing is extrapolated, a slow stream is said; and a whole log becomes the detector's
state and controls in the simulator's channel order, which the detector runs on."""

from __future__ import annotations

import numpy as np
import pytest
from uav_aircraft.airframe import load_airframe
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_common.sample_grid import on_grid
from uav_fault_estimator.detection.calibration_file import (
    read_calibration,
    surface_calibration_path,
)
from uav_fault_estimator.detection.detector import SelfTuningDetector
from uav_fault_estimator.flight_logs.resample import (
    ANGULAR,
    GAP_FACTOR,
    HOLD,
    LINEAR,
    detector_samples,
    grid_times_s,
    resample,
    slow_stream_warning,
)
from uav_fault_estimator.flight_logs.streams import (
    AIRSPEED,
    ATTITUDE,
    BODY_RATES,
    OUTPUTS,
    FlightLog,
    TimedSeries,
)

PERIOD_S = 0.2  # the shipped calibration's sample_period_s
EXAMPLE_AIRFRAME = load_vehicle("aerosonde").airframe_files["aerosonde_sim"]


def series(times_s, values, columns=("x",)) -> TimedSeries:
    values = np.asarray(values, dtype=float)
    return TimedSeries(np.asarray(times_s, dtype=float), values.reshape(len(times_s), len(columns)),
                       tuple(columns))


def jittered_times_s(rng, start_s: float, end_s: float, period_s: float) -> np.ndarray:
    """Instants about period_s apart, each up to 30 % of it early or late."""
    nominal = np.arange(start_s, end_s, period_s)
    return nominal + rng.uniform(-0.3, 0.3, nominal.size) * period_s


@pytest.mark.timeout(10)
def test_the_grid_is_the_multiples_of_the_period_within_the_span():
    grid = grid_times_s(0.05, 1.0, PERIOD_S)
    np.testing.assert_allclose(grid, [0.2, 0.4, 0.6, 0.8, 1.0])
    assert all(on_grid(t, PERIOD_S) for t in grid_times_s(3.0, 500.0, PERIOD_S))
    assert grid_times_s(0.41, 0.59, PERIOD_S).size == 0


@pytest.mark.timeout(10)
def test_a_ramp_at_jittered_instants_is_resampled_exactly():
    rng = np.random.default_rng(17)
    times_s = jittered_times_s(rng, 1.0, 30.0, 0.1)  # 10 Hz, faster than the grid
    ramp = series(times_s, np.column_stack([2.5 * times_s - 4.0, -0.3 * times_s]), ("a", "b"))
    grid = grid_times_s(times_s[0], times_s[-1], PERIOD_S)
    np.testing.assert_allclose(resample(ramp, grid, LINEAR),
                               np.column_stack([2.5 * grid - 4.0, -0.3 * grid]), atol=1e-12)
    slow_times_s = jittered_times_s(rng, 1.0, 30.0, 0.4)  # 2.5 Hz, slower than the grid
    slow = series(slow_times_s, 0.7 * slow_times_s + 1.0)
    grid = grid_times_s(slow_times_s[0], slow_times_s[-1], PERIOD_S)
    np.testing.assert_allclose(resample(slow, grid, LINEAR)[:, 0], 0.7 * grid + 1.0, atol=1e-12)


@pytest.mark.timeout(10)
def test_angles_are_interpolated_the_short_way_round():
    yaw = series([0.0, 0.4], [np.pi - 0.1, -np.pi + 0.1])  # through +-pi, 0.2 rad apart
    values = resample(yaw, np.array([0.0, 0.2, 0.4]), ANGULAR)[:, 0]
    np.testing.assert_allclose(np.abs(values), [np.pi - 0.1, np.pi, np.pi - 0.1], atol=1e-12)
    assert -np.pi < values.min() and values.max() <= np.pi
    assert resample(yaw, np.array([0.2]), LINEAR)[0, 0] == pytest.approx(0.0)  # the long way


@pytest.mark.timeout(10)
def test_a_step_held_lands_on_the_right_grid_points():
    # an output every 0.35 s (2.9 Hz) commanding 1 from its sample at 1.05 s to that at 1.75 s
    times_s = np.round(np.arange(7) * 0.35, 9)
    command = [0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0]
    grid = grid_times_s(0.0, times_s[-1], PERIOD_S)  # 0, 0.2, ..., 2.0
    held = resample(series(times_s, command), grid, HOLD)[:, 0]
    # the first grid point at or after 1.05 s is 1.2 s, the last before 1.75 s is 1.6 s
    np.testing.assert_array_equal(held, [0, 0, 0, 0, 0, 0, 1, 1, 1, 0, 0])


@pytest.mark.timeout(10)
def test_a_sample_on_a_grid_point_is_held_from_that_grid_point():
    # stamps rounded to the microsecond (a ULog): 0.6 s is on the grid whatever 3 * 0.2 gives
    step = series([0.0, 0.3, 0.6, 0.9], [0.0, 0.0, 1.0, 1.0])
    grid = grid_times_s(0.0, 0.9, PERIOD_S)
    np.testing.assert_array_equal(resample(step, grid, HOLD)[:, 0], [0.0, 0.0, 0.0, 1.0, 1.0])


@pytest.mark.timeout(10)
def test_samples_on_the_grid_come_out_unchanged():
    # the project's recordings: 20 Hz stamps in integer nanoseconds, every fourth on the grid
    rng = np.random.default_rng(3)
    times_s = np.arange(0, 60_000_000_000, 50_000_000) / 1e9
    values = rng.uniform(-3.0, 3.0, (times_s.size, 2))  # angles too: within (-pi, pi]
    grid = grid_times_s(times_s[0], times_s[-1], PERIOD_S)
    for method in (LINEAR, ANGULAR, HOLD):
        np.testing.assert_array_equal(resample(series(times_s, values, ("a", "b")), grid,
                                               method), values[::4], err_msg=method)


@pytest.mark.timeout(10)
def test_a_gap_longer_than_the_limit_is_nan_there_and_only_there():
    times_s = np.concatenate([np.arange(0.0, 5.0, 0.1), np.arange(6.0, 10.0, 0.1)])
    ramp = series(times_s, 3.0 * times_s)
    grid = grid_times_s(0.0, times_s[-1], PERIOD_S)
    in_gap = (grid > times_s[49]) & (grid < 6.0)  # after the last sample before it
    for method in (LINEAR, HOLD):
        values = resample(ramp, grid, method)[:, 0]
        assert np.isnan(values[in_gap]).all() and np.isfinite(values[~in_gap]).all(), method
    np.testing.assert_allclose(resample(ramp, grid, LINEAR)[~in_gap, 0], 3.0 * grid[~in_gap],
                               atol=1e-12)
    # a longer limit bridges it
    assert np.isfinite(resample(ramp, grid, LINEAR, gap_s=1.2)).all()


@pytest.mark.timeout(10)
def test_the_default_gap_limit_is_gap_factor_median_periods():
    times_s = np.round(np.arange(0.0, 3.0, 0.1), 9)
    one_lost = np.delete(times_s, [11])  # 1.0 -> 1.2: twice the period, bridged
    two_lost = np.delete(times_s, [11, 12])  # 1.0 -> 1.3: three times, a gap
    assert 2 < GAP_FACTOR < 3
    grid = np.array([1.1, 1.2])
    assert np.isfinite(resample(series(one_lost, one_lost), grid, LINEAR)).all()
    assert np.isnan(resample(series(two_lost, two_lost), grid, LINEAR)).all()


@pytest.mark.timeout(10)
def test_nothing_is_extrapolated_before_the_first_or_after_the_last_sample():
    ramp = series([1.05, 1.5, 2.1, 2.9], [1.05, 1.5, 2.1, 2.9])
    grid = grid_times_s(0.0, 4.0, PERIOD_S)
    for method in (LINEAR, HOLD):
        values = resample(ramp, grid, method)[:, 0]
        inside = (grid >= 1.05) & (grid <= 2.9)
        assert np.isnan(values[~inside]).all() and np.isfinite(values[inside]).all(), method
    assert np.isnan(resample(series([], []), grid, LINEAR)).all()


@pytest.mark.timeout(10)
def test_a_stream_slower_than_the_grid_is_said():
    slow = series(np.arange(0.0, 10.0, 0.4), np.zeros(25))
    assert slow_stream_warning("body_rates", slow, PERIOD_S) == (
        "stream body_rates is slower than the detector's grid: a sample every 0.400 s "
        "(2.50 Hz) against 0.2 s; between its samples the grid points are estimated, not "
        "measured")
    assert slow_stream_warning("body_rates", series(np.arange(0.0, 10.0, 0.1), np.zeros(100)),
                               PERIOD_S) is None


def pwm_log(duration_s: float = 40.0, rates_period_s: float = 0.1,
            outputs_period_s: float = 1 / 2.9, seed: int = 5) -> FlightLog:
    """A synthetic log in the example airframe's PWM: rates and attitude at their own jittered
    instants, outputs at 2.9 Hz, airspeed at 10 Hz."""
    rng = np.random.default_rng(seed)
    rates_t = jittered_times_s(rng, 0.03, duration_s, rates_period_s)
    outputs_t = jittered_times_s(rng, 0.11, duration_s, outputs_period_s)
    airspeed_t = jittered_times_s(rng, 0.0, duration_s, 0.1)
    aileron_us = 1500 + rng.normal(0.0, 60.0, outputs_t.size)
    elevator_us = 1500 + rng.normal(0.0, 30.0, outputs_t.size)
    outputs = np.column_stack([aileron_us, elevator_us, np.full(outputs_t.size, 1600.0),
                               np.full(outputs_t.size, 1500.0)])
    return FlightLog("synthetic", "synthetic.ulg", "ulog", {
        BODY_RATES: series(rates_t, rng.normal(0.0, 0.1, (rates_t.size, 3)),
                           ("roll_rate", "pitch_rate", "yaw_rate")),
        ATTITUDE: series(rates_t, rng.normal(0.0, 0.1, (rates_t.size, 3)),
                         ("roll", "pitch", "yaw")),
        AIRSPEED: series(airspeed_t, 20.0 + 0.1 * airspeed_t, ("airspeed",)),
        OUTPUTS: series(outputs_t, outputs, ("output_1", "output_2", "output_3", "output_4")),
    }, airspeed_source="true")


@pytest.mark.timeout(20)
def test_a_log_becomes_the_detectors_state_and_controls():
    log = pwm_log()
    airframe = load_airframe(EXAMPLE_AIRFRAME)
    inputs = detector_samples(log, airframe, PERIOD_S)
    times_s = inputs.times_s
    assert inputs.state.shape == (times_s.size, len(STATE_CHANNELS))
    assert inputs.controls.shape == (times_s.size, len(CONTROL_CHANNELS))
    assert all(on_grid(t, PERIOD_S) for t in times_s)
    assert times_s[0] >= log.streams[OUTPUTS].times_s[0]  # both rates and outputs have begun
    # what the log has is finite, what it lacks NaN
    has_state = [STATE_CHANNELS.index(c) for c in ("roll", "pitch", "yaw", "roll_rate",
                                                     "pitch_rate", "yaw_rate")]
    has_controls = [CONTROL_CHANNELS.index(c) for c in ("aileron", "elevator", "rudder",
                                                         "throttle")]
    assert np.isfinite(inputs.state[:, has_state]).all()
    assert np.isnan(np.delete(inputs.state, has_state, axis=1)).all()
    assert np.isfinite(inputs.controls[:, has_controls]).all()
    assert np.isnan(np.delete(inputs.controls, has_controls, axis=1)).all()
    np.testing.assert_allclose(inputs.airspeed_mps, 20.0 + 0.1 * times_s, atol=1e-12)
    np.testing.assert_allclose(inputs.controls[:, CONTROL_CHANNELS.index("throttle")], 0.6)
    # the outputs at 2.9 Hz are slower than the grid, and said; nothing else is
    [line] = inputs.warnings
    assert line.startswith("log synthetic.ulg: stream outputs is slower than the detector's")
    # the detector runs on it: every grid point after the first is a detector sample
    detector = SelfTuningDetector(read_calibration(str(surface_calibration_path())),
                                  false_alarm_probability=0.01)
    made = [detector.update(*sample) for sample in zip(*inputs.flight, strict=True)]
    assert sum(sample is not None for sample in made) == times_s.size - 1


@pytest.mark.timeout(20)
def test_a_gap_in_the_rates_skips_those_detector_samples_only():
    log = pwm_log()
    rates = log.streams[BODY_RATES]
    kept = (rates.times_s < 10.0) | (rates.times_s > 12.0)
    streams = dict(log.streams)
    streams[BODY_RATES] = TimedSeries(rates.times_s[kept], rates.values[kept], rates.columns)
    inputs = detector_samples(FlightLog(log.name, log.source, log.format, streams),
                              load_airframe(EXAMPLE_AIRFRAME), PERIOD_S)
    rate_missing = np.isnan(inputs.state[:, STATE_CHANNELS.index("roll_rate")])
    assert (inputs.times_s[rate_missing] > 9.9).all()
    assert (inputs.times_s[rate_missing] < 12.1).all() and rate_missing.sum() >= 9
    detector = SelfTuningDetector(read_calibration(str(surface_calibration_path())),
                                  false_alarm_probability=0.01)
    made = [detector.update(*sample) for sample in zip(*inputs.flight, strict=True)]
    # and the first sample after the gap: its r[k-1] fell in the gap (the yaw model's input)
    after_gap = np.concatenate([[False], rate_missing[:-1]]) & ~rate_missing
    assert after_gap.sum() == 1
    assert [sample is None for sample in made[1:]] == list((rate_missing | after_gap)[1:])


@pytest.mark.timeout(10)
def test_a_log_the_detector_cannot_use_is_one_line():
    log = pwm_log(duration_s=5.0)
    without_rates = FlightLog("x", "x.ulg", "ulog", {OUTPUTS: log.streams[OUTPUTS]})
    with pytest.raises(ValueError, match="no body rates"):
        detector_samples(without_rates, load_airframe(EXAMPLE_AIRFRAME), PERIOD_S)
    with pytest.raises(ValueError, match="need an airframe file"):
        detector_samples(log, None, PERIOD_S)
