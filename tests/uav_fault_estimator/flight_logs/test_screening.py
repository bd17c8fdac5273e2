"""flight_logs.screening on detector samples made up here: alarms per test and channel, runs
merged into intervals (a skipped sample ends one), the summary's counts and the table."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from uav_fault_estimator.detection.detector import DetectorSample
from uav_fault_estimator.flight_logs.screening import (
    TABLE_COLUMNS,
    AlarmInterval,
    alarm_intervals,
    alarm_table,
    log_summary,
    raised_runs,
    write_alarm_csv,
)

PERIOD_S = 0.2
CHANNELS = ("roll", "pitch", "yaw")  # the shipped calibration's generators
THRESHOLD = 10.0  # every test's, in these samples


def sample(time_s: float, statistic: tuple[float, float, float],
           deviation: tuple[float, float, float]) -> DetectorSample:
    """A detector sample with these GLRT statistics and parameter deviations (roll, pitch,
    yaw) against THRESHOLD, alarms as the detector sets them."""
    statistic, deviation = np.array(statistic), np.array(deviation)
    alarm, deviates = statistic > THRESHOLD, deviation > THRESHOLD
    quiet = np.ones(3)  # the fast test's statistic, below THRESHOLD: the self-tuning tests'
    return DetectorSample(
        time_s=time_s, residual=np.zeros(3), statistic=statistic,
        threshold=np.full(3, THRESHOLD), alarm=alarm, parameter_deviation=deviation,
        parameter_deviations=np.repeat(deviation, 2), parameter_threshold=THRESHOLD,
        parameter_alarm=bool(deviates.any()), fixed_residual=np.zeros(3), fast_change=quiet,
        fast_threshold=np.full(3, THRESHOLD), fast_alarm=quiet > THRESHOLD,
        combined_alarm=bool(np.any(alarm & deviates)), theta={}, airspeed_mps=25.0)


QUIET, HIGH, NAN = (1.0, 1.0, 1.0), (20.0, 1.0, 1.0), (math.nan,) * 3
# times: 0.0 to 1.0 s, then 1.4 s (1.2 s skipped) and 1.6 s
SAMPLES = [
    sample(0.0, NAN, NAN),  # not yet settled: never an alarm
    sample(0.2, QUIET, QUIET),
    sample(0.4, HIGH, QUIET),  # roll GLRT
    sample(0.6, HIGH, HIGH),  # roll GLRT, parameter and combined
    sample(0.8, HIGH, (1.0, 20.0, 1.0)),  # roll GLRT, pitch parameter: not combined
    sample(1.0, HIGH, HIGH),
    sample(1.4, HIGH, HIGH),  # after the skipped 1.2 s: new intervals
    sample(1.6, (1.0, 1.0, 20.0), QUIET),  # yaw GLRT
]


@pytest.mark.timeout(10)
def test_runs_follow_one_period_apart() -> None:
    times_s = np.array([0.0, 0.2, 0.4, 0.8, 1.0, 1.2])
    raised = np.array([True, True, False, True, True, True])
    assert raised_runs(times_s, raised, PERIOD_S) == [(0, 1), (3, 5)]
    # consecutive indices but 0.4 s apart (a skipped sample): two runs
    assert raised_runs(times_s, np.array([0, 0, 1, 1, 0, 0], dtype=bool), PERIOD_S) == [
        (2, 2), (3, 3)]
    assert raised_runs(times_s, np.zeros(6, dtype=bool), PERIOD_S) == []


@pytest.mark.timeout(10)
def test_intervals_per_test_and_channel() -> None:
    assert alarm_intervals(SAMPLES, CHANNELS, PERIOD_S) == [
        AlarmInterval(0.4, 1.0, "roll", "glrt", 4),
        AlarmInterval(0.6, 0.6, "roll", "parameter", 1),
        AlarmInterval(0.6, 0.6, "roll", "combined", 1),
        AlarmInterval(0.8, 0.8, "pitch", "parameter", 1),
        AlarmInterval(1.0, 1.0, "roll", "parameter", 1),
        AlarmInterval(1.0, 1.0, "roll", "combined", 1),
        AlarmInterval(1.4, 1.4, "roll", "glrt", 1),
        AlarmInterval(1.4, 1.4, "roll", "parameter", 1),
        AlarmInterval(1.4, 1.4, "roll", "combined", 1),
        AlarmInterval(1.6, 1.6, "yaw", "glrt", 1),
    ]


@pytest.mark.timeout(10)
def test_summary_counts_and_first_alarm() -> None:
    summary = log_summary("flight", "/logs/flight.ulg", SAMPLES, CHANNELS, PERIOD_S,
                          ("a warning",), 0.0)
    assert json.loads(json.dumps(summary)) == summary  # JSON as it is
    assert (summary["samples"], summary["tested_samples"]) == (8, 7)
    assert summary["alarm_samples"] == {
        "glrt": {"any": 6, "roll": 5, "pitch": 0, "yaw": 1},
        "parameter": {"any": 4, "roll": 3, "pitch": 1, "yaw": 0},
        "fast": {"any": 0, "roll": 0, "pitch": 0, "yaw": 0},
        "combined": {"any": 3, "roll": 3, "pitch": 0, "yaw": 0},
    }
    assert summary["alarm_rate"]["combined"] == pytest.approx(3 / 7)
    assert summary["first_combined_alarm_s"] == 0.6
    assert len(summary["intervals"]) == 10
    assert summary["intervals"][0] == {"start_s": 0.4, "end_s": 1.0, "channel": "roll",
                                       "test": "glrt", "samples": 4}
    assert summary["warnings"] == ["a warning"]
    quiet = log_summary("quiet", "q.ulg", SAMPLES[:2], CHANNELS, PERIOD_S, (), 0.0)
    assert (quiet["first_combined_alarm_s"], quiet["intervals"]) == (None, [])


@pytest.mark.timeout(10)
def test_table_and_csv(tmp_path: Path) -> None:
    intervals = alarm_intervals(SAMPLES, CHANNELS, PERIOD_S)
    lines = alarm_table(intervals).splitlines()
    assert lines[0].split() == list(TABLE_COLUMNS)
    assert lines[1].split() == ["0.4", "1.0", "roll", "glrt", "4"]
    assert alarm_table([]) == "no alarms"
    write_alarm_csv(tmp_path / "alarms.csv", intervals, 1500000000.25)
    with open(tmp_path / "alarms.csv", newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert list(rows[0]) == [*TABLE_COLUMNS, "start_stamp_s", "end_stamp_s"]
    assert [AlarmInterval(float(r["start_s"]), float(r["end_s"]), r["channel"], r["test"],
                          int(r["samples"])) for r in rows] == intervals
    assert (rows[0]["start_stamp_s"], rows[0]["end_stamp_s"]) == ("1500000000.65",
                                                                  "1500000001.25")
