"""What mavlink_node tells a ground station over the link, where enabled: the fault
estimates as NAMED_VALUE_FLOAT and the alarms as STATUSTEXT, so that Mission Planner and
QGroundControl show them beside the autopilot's own.

MAVLink's fields are short: a NAMED_VALUE_FLOAT's name holds 10 characters, a STATUSTEXT's
text 50 (pymavlink truncates silently, so the texts here are made to fit). Each estimate
goes out under a short name (SHORT_NAMES); the texts are said on a change only (an estimate
reaching the detection threshold, the detector's combined alarm rising), at most one per
min_interval_s, so that a flickering estimate cannot flood a link that also carries the
autopilot's telemetry.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink
from uav_common.channels import DETECTION_THRESHOLD_PCT

NAME_CHARS = 10  # NAMED_VALUE_FLOAT's name
TEXT_CHARS = 50  # STATUSTEXT's text
TEXT_SEVERITY = mavlink.MAV_SEVERITY_WARNING  # shown and spoken by the ground stations
# The estimator's columns (uav_common.channels.MODEL_FAULT_NAMES) in at most NAME_CHARS.
SHORT_NAMES = {
    "right_wing_lift_loss": "rw_lift",
    "right_wing_drag_increase": "rw_drag",
    "left_wing_lift_loss": "lw_lift",
    "left_wing_drag_increase": "lw_drag",
    "propulsion_loss": "prop_loss",
    "pitch_moment": "pitch_mom",
    "aileron_effectiveness_loss": "ail_eff",
}


def short_name(fault: str) -> str:
    """The fault's NAMED_VALUE_FLOAT name: SHORT_NAMES', else its first NAME_CHARS
    characters."""
    return SHORT_NAMES.get(fault, fault[:NAME_CHARS])


def named_values(names: Sequence[str], values_pct: Sequence[float]) -> list[tuple[str, float]]:
    """(name, value [%]) of each estimate, as NAMED_VALUE_FLOAT carries them."""
    return [(short_name(name), float(value))
            for name, value in zip(names, values_pct, strict=True)]


@dataclass
class AlarmTexts:
    """The STATUSTEXT lines of a flight's estimates and alarms, each said once when it
    starts, at most one per min_interval_s [s, the stamps' time]; what comes within the
    interval is said with the next line."""

    min_interval_s: float
    said_s: float | None = None  # when the last line was said [s]
    pending: list[str] = field(default_factory=list)
    estimates_over: frozenset[str] = frozenset()  # short names at or over the threshold
    alarm_on: bool = False

    def estimates(self, time_s: float, names: Sequence[str],
                  values_pct: Sequence[float]) -> str | None:
        """The line to send for the estimates [%] at time_s [s], or None."""
        values = dict(named_values(names, values_pct))
        over = frozenset(name for name, value in values.items()
                         if value >= DETECTION_THRESHOLD_PCT)
        self.pending += [f"{name} {values[name]:.0f}%"
                         for name in sorted(over - self.estimates_over)]
        self.estimates_over = over
        return self._line(time_s)

    def alarm(self, time_s: float, combined_alarm: bool, channels: Sequence[str]) -> str | None:
        """The line to send for the detector's combined alarm at time_s [s] (channels: the
        generators over their thresholds), or None."""
        if combined_alarm and not self.alarm_on:
            self.pending.append("alarm " + ",".join(channels))
        self.alarm_on = combined_alarm
        return self._line(time_s)

    def _line(self, time_s: float) -> str | None:
        if not self.pending or (self.said_s is not None
                                and time_s - self.said_s < self.min_interval_s):
            return None
        line = "UAV FDI: " + "; ".join(self.pending)
        self.pending.clear()
        self.said_s = time_s
        return line if len(line) <= TEXT_CHARS else line[:TEXT_CHARS - 3] + "..."
