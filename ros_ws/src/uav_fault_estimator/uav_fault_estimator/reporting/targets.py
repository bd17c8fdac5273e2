"""The estimator's default targets, their one home: what a flight's estimates should meet
(docs/estimator.md#targets quotes TARGETS_TEXT). demo.sh says in its last line whether a run
met them; studies.random_aircraft and the tests hold flights to them. No ROS here.

A flight is judged on its metrics (metrics.json's `faults` and `false_alarms`, or
metrics.fault_metrics'): every fault not seeded on its largest estimate after settle_s;
every fault seeded to the detection threshold or beyond on the estimate's RMS error, its
detection delay and its final estimate, each against the fault's final seeded value; and
the flight on its false alarms. A fault whose seeded value reached
the threshold within DETECTED_WITHIN_S of the flight's end is not judged: the flight ended
before it could be found in time (a scenario cut short). Nor is a fault without figures: a
flight no longer than settle_s has none.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from uav_common.channels import DETECTION_THRESHOLD_PCT

# Per seeded fault: the estimate's RMS error after settle_s at most this share of the
# fault's final seeded value; found (the estimate at the threshold) within this many seconds
# of the seeded value reaching the threshold; the final estimate within this share of it.
RMSE_SHARE = 0.15
DETECTED_WITHIN_S = 10.0
FINAL_SHARE = 0.10
# Per fault not seeded: its largest estimate after settle_s below this [%].
FAULT_FREE_BELOW_PCT = DETECTION_THRESHOLD_PCT
TARGETS_TEXT = (
    f"a fault not seeded stays below {FAULT_FREE_BELOW_PCT:g} % after settle_s; a seeded "
    f"fault's estimate has an RMS error of at most {100 * RMSE_SHARE:g} % of its magnitude, "
    f"reaches the {DETECTION_THRESHOLD_PCT:g} % threshold within {DETECTED_WITHIN_S:g} s of the "
    f"seeded value reaching it, and ends within {100 * FINAL_SHARE:g} % of the magnitude; no "
    "false alarm")
TARGETS_PAGE = "docs/estimator.md#targets"
SEEDED_GRID_S = 0.05  # sim_node's default sensor period: the seeded faults' stamps


# Why a fault is not judged
NO_FIGURES = "no estimate after settle_s"
TOO_LATE = f"at the threshold within {DETECTED_WITHIN_S:g} s of the end"


@dataclass(frozen=True)
class Verdict:
    """A flight against the targets: each target missed, a phrase each (empty: all met),
    and the faults not judged, by why (NO_FIGURES, TOO_LATE)."""

    missed: list[str]
    unjudged: dict[str, list[str]]

    def text(self) -> str:
        """The verdict in words, for one line."""
        said = f"missed: {', '.join(self.missed)}" if self.missed else "met"
        if not self.unjudged:
            return said
        return said + " (not judged, " + "; ".join(
            f"{why}: {', '.join(names)}" for why, names in self.unjudged.items()) + ")"


def judge(faults: Mapping[str, Mapping], false_alarms: Sequence[str],
          late: Collection[str] = ()) -> Verdict:
    """The flight's faults (by name, metrics.json's entries) and false alarms against the
    targets; late: the faults reached too late in the flight to judge (reached_late)."""
    missed: list[str] = []
    unjudged: dict[str, list[str]] = {}
    for name, fault in faults.items():
        if fault["seeded"]:
            continue
        if fault["max_abs_error_pct"] is None:
            unjudged.setdefault(NO_FIGURES, []).append(name)
        elif fault["max_abs_error_pct"] >= FAULT_FREE_BELOW_PCT:
            missed.append(f"fault-free {name} {fault['max_abs_error_pct']:.2f} %")
    missed += [f"false alarm {name}" for name in false_alarms]
    seeded = {name: fault for name, fault in faults.items()
              if fault["seeded"] and fault["seeded_final_pct"] >= DETECTION_THRESHOLD_PCT}
    for name, fault in seeded.items():
        if name in late:
            unjudged.setdefault(TOO_LATE, []).append(name)
        elif fault["rmse_pct"] is None:
            unjudged.setdefault(NO_FIGURES, []).append(name)
        else:
            missed += _seeded_misses(name, fault)
    return Verdict(missed, unjudged)


def _seeded_misses(name: str, fault: Mapping) -> list[str]:
    """The targets a seeded fault's figures miss, a phrase each."""
    missed = []
    magnitude = fault["seeded_final_pct"]
    if fault["rmse_pct"] > RMSE_SHARE * magnitude:
        missed.append(f"{name} RMS {fault['rmse_pct']:.2f} % of {magnitude:g}")
    delay = fault["detection_delay_s"]
    if delay is None or delay > DETECTED_WITHIN_S:
        missed.append(f"{name} found {'never' if delay is None else f'{delay:g} s'}")
    if abs(fault["estimate_final_pct"] - magnitude) > FINAL_SHARE * magnitude:
        missed.append(f"{name} final {fault['estimate_final_pct']:.2f} % for {magnitude:g}")
    return missed


def reached_late(duration_s: float,
                 faults_pct: Callable[[float], Mapping[str, float]]) -> list[str]:
    """The faults whose seeded value (faults_pct(time_s) [%], a scenario's) reaches the
    detection threshold in a flight's last DETECTED_WITHIN_S of duration_s [s] (on sim_node's
    default sensor grid)."""
    times_s = np.arange(0.0, duration_s + SEEDED_GRID_S / 2, SEEDED_GRID_S)
    late_s = duration_s - DETECTED_WITHIN_S
    values = [faults_pct(time_s) for time_s in times_s]
    late = []
    for name in values[0]:
        reached = [t for t, value in zip(times_s, values, strict=True)
                   if value[name] >= DETECTION_THRESHOLD_PCT]
        if reached and reached[0] > late_s:
            late.append(name)
    return late
