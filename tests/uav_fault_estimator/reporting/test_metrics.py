"""metrics.json's figures on series whose answers are known in closed form."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from uav_fault_estimator.reporting.metrics import (
    AlarmSeries,
    EstimateSeries,
    SeededSeries,
    alarm_metrics,
    fault_metrics,
    flow_angle_rms_deg,
    solver_metrics,
)

NAMES = ("ramp_fault", "step_fault", "quiet_fault", "noisy_fault")
SEEDED_STAMPS = np.round(np.arange(0, 6001) * 0.05, 6)         # 0 ... 300 s at 20 Hz
ESTIMATE_STAMPS = np.round(np.arange(1, 601) * 0.5, 6)         # 0.5 ... 300 s


def seeded_pct(stamps_s: np.ndarray) -> np.ndarray:
    ramp = 10.0 * np.clip((stamps_s - 60.0) / 40.0, 0.0, 1.0)  # 60-100 s to 10 %
    step = np.where(stamps_s > 150.0, 25.0, 0.0)               # after 150 s: 25 %
    zero = np.zeros_like(stamps_s)
    return np.stack([ramp, step, zero, zero], axis=1)


def series(offset_pct: float = 0.0, noisy_spike_s: float = 100.0):
    seeded = SeededSeries(NAMES, SEEDED_STAMPS, seeded_pct(SEEDED_STAMPS))
    values = seeded_pct(ESTIMATE_STAMPS) + offset_pct
    values[:, 2:] = 0.0
    values[noisy_spike_s == ESTIMATE_STAMPS, 3] = 2.5
    statuses = np.zeros(ESTIMATE_STAMPS.size, dtype=int)
    statuses[:20] = 4   # waiting
    statuses[100] = 1   # one update stopped at the iteration limit
    times = np.linspace(0.2, 1.2, ESTIMATE_STAMPS.size)
    return EstimateSeries(NAMES, ESTIMATE_STAMPS, values, statuses, times), seeded


@pytest.mark.timeout(30)
def test_errors_delays_and_false_alarms():
    estimates, seeded = series()
    faults, false_alarms = fault_metrics(estimates, seeded, settle_s=20.0, threshold_pct=2.0)
    ramp, step = faults["ramp_fault"], faults["step_fault"]
    assert ramp["seeded"] and step["seeded"] and not faults["quiet_fault"]["seeded"]
    assert ramp["rmse_pct"] == 0.0 and ramp["max_abs_error_pct"] == 0.0
    # the ramp reaches 2 % at 68 s, an estimate stamp: found at once
    assert ramp["detection_delay_s"] == pytest.approx(0.0)
    # the step's first seeded stamp above 2 % is 150.05 s, the next estimate stamp 150.5 s
    assert step["detection_delay_s"] == pytest.approx(0.45)
    assert step["seeded_final_pct"] == 25.0 and step["estimate_final_pct"] == 25.0
    assert false_alarms == ["noisy_fault"]


@pytest.mark.timeout(30)
def test_an_estimate_rising_before_its_fault_is_a_false_alarm():
    """Estimates 0.5 % above the truth reach 2 % at 66 s, before the ramp does (68 s)."""
    estimates, seeded = series(offset_pct=0.5)
    faults, false_alarms = fault_metrics(estimates, seeded, settle_s=20.0, threshold_pct=2.0)
    assert false_alarms == ["ramp_fault", "noisy_fault"]
    assert faults["ramp_fault"]["rmse_pct"] == pytest.approx(0.5)
    assert faults["ramp_fault"]["detection_delay_s"] == pytest.approx(0.0)
    assert "step_fault" not in false_alarms  # 0.5 % before its step: below the threshold


@pytest.mark.timeout(30)
def test_a_spike_before_settling_is_no_false_alarm():
    estimates, seeded = series(noisy_spike_s=10.0)
    faults, false_alarms = fault_metrics(estimates, seeded, settle_s=20.0, threshold_pct=2.0)
    assert false_alarms == [] and faults["noisy_fault"]["detection_delay_s"] is None
    assert faults["ramp_fault"]["rmse_pct"] == 0.0


@pytest.mark.timeout(30)
def test_flow_angle_rms_leaves_out_the_settling_and_the_samples_without_air_data():
    """Errors of 1 deg in alpha and 2 deg in beta after settling, 30 deg before it and NaN
    where no air data was published: the RMS is 1 and 2 deg; None without any."""
    estimates, _ = series()
    errors = np.tile(np.radians([1.0, -2.0]), (ESTIMATE_STAMPS.size, 1))
    errors[ESTIMATE_STAMPS < 20.0] = np.radians(30.0)
    errors[::7] = np.nan
    with_errors = dataclasses.replace(estimates, flow_angle_errors_rad=errors)
    assert flow_angle_rms_deg(with_errors, settle_s=20.0) == pytest.approx([1.0, 2.0])
    assert flow_angle_rms_deg(estimates, settle_s=20.0) is None
    none_published = dataclasses.replace(estimates, flow_angle_errors_rad=errors * np.nan)
    assert flow_angle_rms_deg(none_published, settle_s=20.0) is None


@pytest.mark.timeout(30)
def test_solver_figures_count_failures_but_not_waiting():
    estimates, _ = series()
    solver = solver_metrics(estimates)
    solved_times = estimates.solve_times_ms[estimates.statuses == 0]
    assert solver["solves"] == 600 - 20 - 1 and solver["failures"] == 1
    assert solver["median_ms"] == pytest.approx(np.median(solved_times), abs=1e-3)
    assert solver["max_ms"] == pytest.approx(1.2, abs=1e-3)
    assert solver["cpu_median_ms"] is None  # not in the series: a recording without it
    with_cpu = dataclasses.replace(estimates, cpu_times_ms=estimates.solve_times_ms / 2)
    assert solver_metrics(with_cpu)["cpu_median_ms"] == pytest.approx(
        np.median(solved_times) / 2, abs=1e-3)
    assert solver["name"] == "proxsuite"  # a recording from before mhe_node named it
    named = dataclasses.replace(estimates, solver_method="active_set")
    assert solver_metrics(named)["name"] == "active_set"


@pytest.mark.timeout(30)
def test_alarm_counts_rates_and_delays():
    """Tested from 30 s (the RLS settling), the ramp fault starts at 60 s: 150 fault-free
    tested samples at 0.2 s. Roll alarms at 40 s (fault-free) and from 65 s; the parameters
    only at 61 s; the roll fast test from 62 s; the engine cut's template at 45 s and from
    63 s; the combined alarm (as given) never."""
    stamps = np.round(np.arange(1, 1501) * 0.2, 6)
    roll = (stamps == 40.0) | (stamps >= 65.0)
    alarms = AlarmSeries(
        channel_names=["roll"], stamps_s=stamps, alarm=roll[:, None],
        parameter_alarm=stamps == 61.0, combined_alarm=np.zeros(stamps.size, dtype=bool),
        tested=stamps >= 30.0, false_alarm_probability=0.01,
        fast_alarm=(stamps >= 62.0)[:, None], template_kinds=["engine_cut"],
        template_alarm=((stamps == 45.0) | (stamps >= 63.0))[:, None])
    seeded = SeededSeries(NAMES, SEEDED_STAMPS, seeded_pct(SEEDED_STAMPS))
    summary = alarm_metrics(alarms, seeded)
    assert summary["fault_start_s"] == pytest.approx(60.0)
    assert summary["fault_free_samples"] == 150
    assert summary["tests"]["roll"] == {"fault_free_alarms": 1,
                                        "fault_free_alarm_rate": round(1 / 150, 5),
                                        "first_alarm_delay_s": pytest.approx(5.0)}
    assert summary["tests"]["parameters"]["first_alarm_delay_s"] == pytest.approx(1.0)
    assert summary["tests"]["fast_roll"] == {"fault_free_alarms": 0,
                                             "fault_free_alarm_rate": 0.0,
                                             "first_alarm_delay_s": pytest.approx(2.0)}
    assert summary["tests"]["template_engine_cut"] == {
        "fault_free_alarms": 1, "fault_free_alarm_rate": round(1 / 150, 5),
        "first_alarm_delay_s": pytest.approx(3.0)}
    assert list(summary["tests"]) == ["roll", "parameters", "fast_roll", "template_engine_cut",
                                      "combined"]
    assert summary["tests"]["combined"] == {"fault_free_alarms": 0, "fault_free_alarm_rate": 0.0,
                                            "first_alarm_delay_s": None}
