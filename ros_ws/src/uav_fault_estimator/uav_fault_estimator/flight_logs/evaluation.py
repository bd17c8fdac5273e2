"""A screening held against the ground truth (ground_truth.py): per flight whether and when
the detector's combined alarm saw the failure, on which channel, and what it raised before;
over flights the counts ALFA's authors and Keipour et al. report. No ROS here.

Counted per flight, each flight once:
- a failure flight whose first combined alarm comes at or after the onset: a true positive
  (tp), its delay the time from the onset to that alarm;
- a failure flight with a combined alarm before its onset: a false positive (fp), whatever
  follows (the alarm was raised on a healthy aircraft);
- a failure flight without a combined alarm: a false negative (fn);
- a flight without failure: fp with any combined alarm, else a true negative (tn).
precision tp / (tp + fp), recall tp / (tp + fn), accuracy (tp + tn) / flights.

ALFA's evaluator (castacks/alfa-dataset-tools) also counts a first alarm later than
ALFA_DETECTION_LIMIT_S after the onset as a miss (fn): within_limit(). Summaries are given
over all flights and per failure kind (alfa_summary; KIND_ORDER, Keipour et al.'s table's
rows).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from uav_fault_estimator.detection.detector import DetectorSample
from uav_fault_estimator.flight_logs.ground_truth import FlightTruth
from uav_fault_estimator.flight_logs.screening import COMBINED, TIME_DECIMALS, channel_alarms

# A first alarm later than this after the onset is a miss in ALFA's evaluator [s].
ALFA_DETECTION_LIMIT_S = 5.0
# The failure kinds a summary is given for, in Keipour et al.'s order; two failed parts are
# one kind, their names sorted and joined by '+'.
NO_FAILURE_KIND = "none"
KIND_ORDER = ("engine", "aileron", "elevator", "rudder", "aileron+rudder", NO_FAILURE_KIND)


@dataclass(frozen=True)
class FlightOutcome:
    """One flight against its truth: flight (the log's name), failure and onset_stamp_s (the
    truth), first_alarm_stamp_s and first_alarm_channel (the first combined alarm at or
    after the onset, or anywhere in a flight without failure; stamps in the log's clock [s]),
    alarms_before_onset (combined-alarm samples before the onset; every one without a
    failure), outcome (tp, fp, fn, tn), delay_s (onset to first alarm, tp only),
    right_channel (whether the first alarm's channel is one the failure acts on; tp only),
    flown_after_onset_s (how much log follows the onset) and end_stamp_s (the last sample)."""

    flight: str
    failure: str | None
    onset_stamp_s: float | None
    first_alarm_stamp_s: float | None
    first_alarm_channel: str | None
    alarms_before_onset: int
    outcome: str
    delay_s: float | None
    right_channel: bool | None
    flown_after_onset_s: float | None
    end_stamp_s: float


def flight_outcome(flight: str, truth: FlightTruth, samples: Sequence[DetectorSample],
                   channels: Sequence[str], start_stamp_s: float) -> FlightOutcome:
    """The outcome of one screened flight: its detector samples (times from the log's start,
    start_stamp_s that start in the log's clock [s]), channels the order of their arrays."""
    stamps_s = start_stamp_s + np.array([sample.time_s for sample in samples])
    raised = channel_alarms(samples, len(channels))[COMBINED]
    end_stamp_s = float(stamps_s[-1]) if stamps_s.size else start_stamp_s
    return alarms_outcome(flight, truth, stamps_s, raised, channels, truth.expected_channels,
                          end_stamp_s)


def alarms_outcome(flight: str, truth: FlightTruth, stamps_s: np.ndarray, raised: np.ndarray,
                   channels: Sequence[str], right_channels: Sequence[str],
                   end_stamp_s: float) -> FlightOutcome:
    """The outcome of any detector's alarms: raised (K, len(channels)) bool, which channel
    alarmed at each of the stamps_s (K,) [s, the log's clock]; right_channels the channels
    that read what the failure acts on; end_stamp_s the flight's last sample [s]. Counted as
    the module's docstring says."""
    stamps_s = np.asarray(stamps_s, dtype=float)
    raised = np.asarray(raised, dtype=bool).reshape(stamps_s.size, len(channels))
    alarmed = raised.any(axis=1)
    onset = truth.onset_stamp_s
    before = alarmed & (stamps_s < onset) if onset is not None else alarmed
    after = np.flatnonzero(alarmed & (stamps_s >= onset)) if onset is not None else (
        np.flatnonzero(alarmed))
    first = int(after[0]) if after.size else None
    channel = channels[int(np.argmax(raised[first]))] if first is not None else None
    if onset is None:
        outcome = "fp" if alarmed.any() else "tn"
    else:
        outcome = "fp" if before.any() else ("tp" if first is not None else "fn")
    return FlightOutcome(
        flight=flight, failure=truth.failure, onset_stamp_s=onset,
        first_alarm_stamp_s=None if first is None else _stamp(stamps_s[first]),
        first_alarm_channel=channel, alarms_before_onset=int(before.sum()), outcome=outcome,
        delay_s=_stamp(stamps_s[first] - onset) if outcome == "tp" else None,
        right_channel=channel in right_channels if outcome == "tp" else None,
        flown_after_onset_s=None if onset is None else _stamp(end_stamp_s - onset),
        end_stamp_s=_stamp(end_stamp_s))


def within_limit(outcome: FlightOutcome,
                 limit_s: float = ALFA_DETECTION_LIMIT_S) -> FlightOutcome:
    """The outcome as ALFA's evaluator counts it: a true positive whose delay exceeds
    limit_s [s] is a miss (fn, without delay or channel); every other outcome as it is."""
    if outcome.outcome != "tp" or outcome.delay_s <= limit_s:
        return outcome
    return replace(outcome, outcome="fn", delay_s=None, right_channel=None)


def failure_kind(outcome: FlightOutcome) -> str:
    """The flight's failure kind as KIND_ORDER spells it."""
    if outcome.failure is None:
        return NO_FAILURE_KIND
    return "+".join(sorted(set(outcome.failure.split("+"))))


def _stamp(value: float) -> float:
    return round(float(value), TIME_DECIMALS)


SUMMARY_KEYS = ("tp", "fp", "fn", "tn", "precision", "recall", "accuracy", "mean_delay_s",
                "max_delay_s", "right_channel")


def evaluation_summary(outcomes: Sequence[FlightOutcome]) -> dict[str, Any]:
    """SUMMARY_KEYS: the counts over flights (the module's docstring), the delays of the true
    positives [s] (mean and largest; None without any) and how many of them alarmed first on
    a channel the failure acts on."""
    counts = {kind: sum(o.outcome == kind for o in outcomes) for kind in ("tp", "fp", "fn", "tn")}
    tp, fp, fn, tn = counts.values()
    delays = [o.delay_s for o in outcomes if o.outcome == "tp"]
    return {
        **counts,
        "precision": tp / (tp + fp) if tp + fp else None,
        "recall": tp / (tp + fn) if tp + fn else None,
        "accuracy": (tp + tn) / len(outcomes) if outcomes else None,
        "mean_delay_s": _stamp(np.mean(delays)) if delays else None,
        "max_delay_s": _stamp(max(delays)) if delays else None,
        "right_channel": sum(bool(o.right_channel) for o in outcomes),
    }


def outcome_dict(outcome: FlightOutcome) -> dict[str, Any]:
    """The outcome as JSON-ready data."""
    return asdict(outcome)


OUTCOME_HEADING = (f"{'flight':<58} {'failure':<9} {'outcome':<7} {'delay_s':>7} "
                   f"{'channel':<14} {'before':>6} {'after_s':>7}")


def outcome_line(outcome: FlightOutcome) -> str:
    """One flight as a line of the evaluation table (OUTCOME_HEADING)."""
    delay = "" if outcome.delay_s is None else f"{outcome.delay_s:.1f}"
    after = "" if outcome.flown_after_onset_s is None else f"{outcome.flown_after_onset_s:.1f}"
    return (f"{outcome.flight:<58} {outcome.failure or '-':<9} {outcome.outcome:<7} "
            f"{delay:>7} {outcome.first_alarm_channel or '-':<14} "
            f"{outcome.alarms_before_onset:>6} {after:>7}")


def summary_line(summary: dict[str, Any]) -> str:
    """The summary in one line."""
    def percent(value: float | None) -> str:
        return "-" if value is None else f"{100 * value:.1f} %"

    def seconds(value: float | None) -> str:
        return "-" if value is None else f"{value:.1f} s"

    return (f"tp {summary['tp']}, fp {summary['fp']}, fn {summary['fn']}, tn {summary['tn']}; "
            f"precision {percent(summary['precision'])}, recall {percent(summary['recall'])}, "
            f"accuracy {percent(summary['accuracy'])}; delay mean "
            f"{seconds(summary['mean_delay_s'])}, largest {seconds(summary['max_delay_s'])}; "
            f"first alarm on a channel of the failed part {summary['right_channel']} of "
            f"{summary['tp']}")


def limit_key(key: str, limit_s: float) -> str:
    """A summary key counted within limit_s [s]: `tp` -> `tp_5s`, `mean_delay_s` ->
    `mean_delay_5s` (the benchmark record's names, docs/design.md#the-alfa-benchmarks-record)."""
    return f"{key.removesuffix('_s')}_{limit_s:g}s"


def _both_counts(outcomes: Sequence[FlightOutcome], limit_s: float) -> dict[str, Any]:
    """evaluation_summary() at any delay, and within limit_s [s] under limit_key() names."""
    within = evaluation_summary([within_limit(outcome, limit_s) for outcome in outcomes])
    return {**evaluation_summary(outcomes),
            **{limit_key(key, limit_s): value for key, value in within.items()}}


def alfa_summary(outcomes: Sequence[FlightOutcome],
                 limit_s: float = ALFA_DETECTION_LIMIT_S) -> dict[str, Any]:
    """A benchmark's summary: evaluation_summary() at any delay (`tp`, ...) and within
    limit_s [s] as ALFA's evaluator counts (within_limit(): `tp_5s`, ...), over all flights
    and per failure kind (`by_kind`, each with its `flights`, in KIND_ORDER)."""
    kinds = sorted({failure_kind(o) for o in outcomes},
                   key=lambda kind: (KIND_ORDER.index(kind) if kind in KIND_ORDER
                                     else len(KIND_ORDER), kind))
    return {"detection_limit_s": limit_s, **_both_counts(outcomes, limit_s),
            "by_kind": {kind: {"flights": len(group), **_both_counts(group, limit_s)}
                        for kind in kinds
                        for group in [[o for o in outcomes if failure_kind(o) == kind]]}}


def within_counts(counts: Mapping[str, Any], limit_s: float) -> dict[str, Any]:
    """The counts within limit_s [s] of an alfa_summary() (or of one of its kinds), under
    evaluation_summary()'s names."""
    return {key: counts[limit_key(key, limit_s)] for key in SUMMARY_KEYS}


def kind_lines(summary: Mapping[str, Any]) -> list[str]:
    """Keipour et al.'s table from an alfa_summary(): per failure kind the flights, those
    found (at any delay, and within the limit as ALFA's evaluator counts), mean and largest
    delay [s] of each, and the flights alarmed before their onset or without a failure (fp)."""
    def seconds(value: float | None) -> str:
        return "-" if value is None else f"{value:.1f}"

    limit_s = summary["detection_limit_s"]
    found_within = f"found<={limit_s:g}s"
    lines = [f"{'kind':<15} {'flights':>7} {'found':>5} {'mean_s':>6} {'max_s':>6}   "
             f"{found_within:>11} {'mean_s':>6} {'max_s':>6} {'fp':>3}"]
    for kind, every in summary["by_kind"].items():
        counted = within_counts(every, limit_s)
        lines.append(f"{kind:<15} {every['flights']:>7} {every['tp']:>5} "
                     f"{seconds(every['mean_delay_s']):>6} {seconds(every['max_delay_s']):>6}   "
                     f"{counted['tp']:>11} {seconds(counted['mean_delay_s']):>6} "
                     f"{seconds(counted['max_delay_s']):>6} {every['fp']:>3}")
    return lines
