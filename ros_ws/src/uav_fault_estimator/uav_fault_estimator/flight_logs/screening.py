"""Flight logs screened by the self-tuning detector (scripts/screen_logs.py): one
log's detector samples as alarm intervals, counts and a summary, its table and its figure.
No ROS here.

Four tests, each per channel (the calibration's generators, in its order): "glrt" the channel's
GLRT statistic over its threshold, "parameter" the channel's largest normalised parameter
deviation over the parameter threshold, "fast" the channel's fast window test over its
threshold, "combined" the first two on the same channel or the fast one (the detector's
combined alarm is raised when some channel's is). An interval is a run of consecutive
detector samples (one sample period apart: a skipped sample ends it) on which a test
alarmed on a channel, from the first such sample's time to the last's.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")  # no display: figures are files
import matplotlib.pyplot as plt
import numpy as np
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_common.sample_grid import GRID_TOLERANCE_S

from uav_fault_estimator.detection.detector import DetectorSample, first_combined_alarm
from uav_fault_estimator.flight_logs.resample import DetectorInputs
from uav_fault_estimator.reporting.figures import save_figure, shade_alarms

TESTS = ("glrt", "parameter", "fast", "combined")
COMBINED = "combined"
# Times in the outputs: the grid's stamps are whole microseconds (sample_grid).
TIME_DECIMALS = 6


@dataclass(frozen=True)
class AlarmInterval:
    """A run of consecutive samples on which one test alarmed on one channel: start_s and
    end_s the first and last sample's times [s from the log's start], samples their count."""

    start_s: float
    end_s: float
    channel: str
    test: str
    samples: int


def channel_alarms(samples: Sequence[DetectorSample], channels: int) -> dict[str, np.ndarray]:
    """Per test (TESTS), which samples alarmed on which of the channels: (K, channels) bool
    in the calibration's order (a NaN statistic or deviation, before the detector settles,
    never alarms)."""
    glrt = np.array([sample.alarm for sample in samples], dtype=bool).reshape(-1, channels)
    parameter = np.array([sample.parameter_deviation > sample.parameter_threshold
                          for sample in samples], dtype=bool).reshape(-1, channels)
    fast = np.array([sample.fast_alarm for sample in samples], dtype=bool).reshape(-1, channels)
    combined = np.array([sample.channel_combined_alarm for sample in samples],
                        dtype=bool).reshape(-1, channels)
    return {"glrt": glrt, "parameter": parameter, "fast": fast, COMBINED: combined}


def raised_runs(times_s: np.ndarray, raised: np.ndarray,
                period_s: float) -> list[tuple[int, int]]:
    """(first, last) indices of each run of raised samples whose times_s [s] follow one
    another by one period_s [s]."""
    runs: list[tuple[int, int]] = []
    for k in map(int, np.flatnonzero(raised)):
        if runs and runs[-1][1] == k - 1 and (
                times_s[k] - times_s[k - 1] <= period_s + GRID_TOLERANCE_S):
            runs[-1] = (runs[-1][0], k)
        else:
            runs.append((k, k))
    return runs


def alarm_intervals(samples: Sequence[DetectorSample], channels: Sequence[str],
                    period_s: float) -> list[AlarmInterval]:
    """Every test's alarm intervals on every one of the channels (the calibration's), by
    start time (then channels, TESTS order); period_s the detector's sample period [s]."""
    times_s = np.array([sample.time_s for sample in samples])
    intervals = []
    for test, raised in channel_alarms(samples, len(channels)).items():
        for c, channel in enumerate(channels):
            intervals += [AlarmInterval(round(float(times_s[first]), TIME_DECIMALS),
                                        round(float(times_s[last]), TIME_DECIMALS),
                                        channel, test, last - first + 1)
                          for first, last in raised_runs(times_s, raised[:, c], period_s)]
    return sorted(intervals, key=lambda i: (i.start_s, list(channels).index(i.channel),
                                            TESTS.index(i.test)))


def first_combined_alarm_s(samples: Sequence[DetectorSample],
                           after_s: float = -math.inf) -> float | None:
    """The time [s] of the first combined alarm at or after after_s [s]; None without one."""
    first = first_combined_alarm(samples, after_s)
    return None if first is None else round(first.time_s, TIME_DECIMALS)


def log_summary(name: str, source: str, samples: Sequence[DetectorSample],
                channels: Sequence[str], period_s: float, warnings: Sequence[str],
                start_stamp_s: float) -> dict[str, Any]:
    """A log's screening as JSON-ready data: its name and source (path), samples (the
    detector's), tested_samples (those with every GLRT statistic: after the settling and
    the window), alarm_samples per test (per channel and "any"), the any-channel alarm rate
    per tested sample, the first combined alarm [s], the intervals, the log's warnings and
    start_stamp_s, the instant its times count from in its own clock [s]."""
    alarms = channel_alarms(samples, len(channels))
    tested = int(sum(np.isfinite(sample.statistic).all() for sample in samples))
    counts = {test: {"any": int(raised.any(axis=1).sum()),
                     **{channel: int(raised[:, c].sum()) for c, channel in enumerate(channels)}}
              for test, raised in alarms.items()}
    return {
        "log": name,
        "source": source,
        "start_stamp_s": start_stamp_s,
        "channels": list(channels),
        "samples": len(samples),
        "tested_samples": tested,
        "alarm_samples": counts,
        "alarm_rate": {test: (count["any"] / tested if tested else None)
                       for test, count in counts.items()},
        "first_combined_alarm_s": first_combined_alarm_s(samples),
        "intervals": [asdict(interval)
                      for interval in alarm_intervals(samples, channels, period_s)],
        "warnings": list(warnings),
    }


TABLE_COLUMNS = ("start_s", "end_s", "channel", "test", "samples")


def alarm_table(intervals: Sequence[AlarmInterval]) -> str:
    """The intervals as an aligned text table, one line per interval under a heading
    (TABLE_COLUMNS); "no alarms" without any."""
    if not intervals:
        return "no alarms"
    lines = [f"{'start_s':>10} {'end_s':>10}  {'channel':<7} {'test':<9} {'samples':>7}"]
    lines += [f"{i.start_s:10.1f} {i.end_s:10.1f}  {i.channel:<7} {i.test:<9} {i.samples:7d}"
              for i in intervals]
    return "\n".join(lines)


STAMP_COLUMNS = ("start_stamp_s", "end_stamp_s")  # the CSV's: in the log's own clock


def write_alarm_csv(path: Path, intervals: Sequence[AlarmInterval],
                    start_stamp_s: float) -> None:
    """The intervals as CSV with the header TABLE_COLUMNS and STAMP_COLUMNS, the latter the
    interval's ends in the log's own clock (start_stamp_s the log's start there [s])."""
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(TABLE_COLUMNS + STAMP_COLUMNS)
        writer.writerows([*(getattr(interval, column) for column in TABLE_COLUMNS),
                          *(round(start_stamp_s + time_s, TIME_DECIMALS)
                            for time_s in (interval.start_s, interval.end_s))]
                         for interval in intervals)


def plot_screening(title: str, inputs: DetectorInputs, samples: Sequence[DetectorSample],
                   channels: Sequence[str], intervals: Sequence[AlarmInterval],
                   period_s: float, path: Path, onset_s: float | None = None,
                   detection_limit_s: float | None = None) -> Path:
    """One log's figure: body rates and surfaces [deg], airspeed (the log's and the filtered
    one the schedule used) [m/s], each channel's GLRT statistic over its threshold and the
    parameter deviations over theirs (log scale), the combined alarm intervals shaded on
    every panel (each sample widened by half a period_s [s] either side), and a failure's
    onset_s [s from the log's start] as a line on every panel, followed by the window of
    detection_limit_s [s] in which a first alarm counts (ALFA's evaluator) when given."""
    times_s = np.array([sample.time_s for sample in samples])
    combined = [(i.start_s - period_s / 2, i.end_s + period_s / 2)
                for i in intervals if i.test == COMBINED]
    figure, axes = plt.subplots(4 + len(channels), 1, figsize=(10, 6 + 2 * len(channels)),
                                sharex=True)
    for name in ("roll_rate", "pitch_rate", "yaw_rate"):
        axes[0].plot(inputs.times_s, np.degrees(inputs.state[:, STATE_CHANNELS.index(name)]),
                     label=name, linewidth=0.8)
    axes[0].set_ylabel("body rate [deg/s]")
    for name in ("aileron", "elevator", "rudder"):
        axes[1].plot(inputs.times_s,
                     np.degrees(inputs.controls[:, CONTROL_CHANNELS.index(name)]),
                     label=name, linewidth=0.8)
    axes[1].set_ylabel("surface [deg]")
    axes[2].plot(inputs.times_s, inputs.airspeed_mps, label="log", linewidth=0.8)
    axes[2].plot(times_s, [sample.airspeed_mps for sample in samples], label="filtered")
    axes[2].set_ylabel("airspeed [m/s]")
    for c, channel in enumerate(channels):
        statistic = np.array([sample.statistic[c] for sample in samples])
        axes[3 + c].semilogy(times_s, np.where(statistic > 0, statistic, math.nan),
                             label="statistic")
        axes[3 + c].semilogy(times_s, [sample.threshold[c] for sample in samples], "k:",
                             label="threshold")
        axes[3 + c].set_ylabel(f"GLRT {channel}")
    deviation = np.array([sample.parameter_deviation for sample in samples])
    for c, channel in enumerate(channels):
        axes[-1].semilogy(times_s, deviation[:, c], label=channel, linewidth=0.8)
    axes[-1].semilogy(times_s, [sample.parameter_threshold for sample in samples], "k:",
                      label="threshold")
    axes[-1].set_ylabel("parameter deviation")
    for axis in axes:
        shade_alarms(axis, combined)
        if onset_s is not None:
            axis.axvline(onset_s, color="r", linestyle="--", linewidth=1.0, label="onset")
            if detection_limit_s is not None:
                axis.axvspan(onset_s, onset_s + detection_limit_s, color="g", alpha=0.12,
                             label=f"first {detection_limit_s:g} s")
        axis.legend(fontsize=7, loc="upper left")
    axes[0].set_title(title)
    axes[-1].set_xlabel(f"time from the log's start [s] (its stamp: {inputs.start_stamp_s:.6f} s)")
    return save_figure(figure, path)
