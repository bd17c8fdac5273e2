"""What mavlink_node tells a ground station over the link, where enabled: the fault
estimates as NAMED_VALUE_FLOAT and the alarms as STATUSTEXT, so that Mission Planner,
QGroundControl and MAVProxy show them beside the autopilot's own (docs/onboard.md).

MAVLink's fields are short: a NAMED_VALUE_FLOAT's name holds 10 characters, a STATUSTEXT's
text 50 (pymavlink truncates silently), so every text here is made to fit whole. Each
estimate goes out under a short name (SHORT_NAMES). A text is said on a change only: the
detector's combined alarm starting (WARNING: its cause, as faults/alarm names it, and the
tests that raised it) and ending (NOTICE: how long it lasted), an estimate crossing the
detection threshold upwards (WARNING) or back (NOTICE), with its value. An alarm, or an
estimate over the threshold, that stops for less than `hold_s` of flight time and starts
again goes on, so a flickering test or an estimate hovering at the threshold is one onset
and one end. Texts leave at most one per `min_interval_s` of wall time, in order; an
estimate's text still waiting when its estimate is back under is withdrawn (the value
NAMED_VALUE_FLOAT carries says the rest), and at most MAX_WAITING texts wait (further ones
are counted, not sent).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink
from uav_common.channels import DETECTION_THRESHOLD_PCT

NAME_CHARS = 10  # NAMED_VALUE_FLOAT's name
TEXT_CHARS = 50  # STATUSTEXT's text
PREFIX = "UAV FDI"  # every text's first word, so a ground station's reader knows its source
ALARM_SEVERITY = mavlink.MAV_SEVERITY_WARNING  # shown and spoken by the ground stations
END_SEVERITY = mavlink.MAV_SEVERITY_NOTICE  # shown, not alarming
MAX_WAITING = 20  # texts held back by the interval; more are counted as dropped
TEXT_INTERVAL_S = 1.0  # default least wall time between two texts [s]
# Default flight time an alarm or estimate stays off before its end is said [s]: on the
# default flight the detector's combined alarm pauses for 3-10 s within one failure.
HOLD_S = 10.0
# The detector's tests, as the texts name them: the self-tuning test (a channel's GLRT and
# its parameter test agreeing, Blanke & Hansen section III.D), the fast window test and the
# template (learned failure shape) test: the three that raise the combined alarm.
TEST_WORDS = ("glrt", "fast", "shape")
UNKNOWN_CAUSE = "unknown"  # an alarm whose detector names no cause
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


def alarm_tests(glrt_alarm: Sequence[bool], parameter_deviation: Sequence[float],
                parameter_threshold: float, fast_alarm: Sequence[bool],
                template_alarm: Sequence[bool]) -> tuple[str, ...]:
    """The TEST_WORDS of the tests raising a combined alarm, from faults/alarm's fields:
    per channel the GLRT alarm, the parameter deviation and the fast alarm, the parameter
    threshold, per template its alarm. ValueError when the per-channel arrays differ in
    length."""
    self_tuning = any(alarm and deviation > parameter_threshold
                      for alarm, deviation in zip(glrt_alarm, parameter_deviation,
                                                  strict=True))
    raised = (self_tuning, any(fast_alarm), any(template_alarm))
    return tuple(word for word, on in zip(TEST_WORDS, raised, strict=True) if on)


def alarm_onset_text(cause: str, tests: Sequence[str]) -> str:
    """`UAV FDI alarm: CAUSE (TESTS)`; without the tests where they would not fit."""
    text = f"{PREFIX} alarm: {cause or UNKNOWN_CAUSE}"
    with_tests = f"{text} ({','.join(tests)})" if tests else text
    return with_tests if len(with_tests) <= TEXT_CHARS else text[:TEXT_CHARS]


def alarm_end_text(cause: str, duration_s: float) -> str:
    """`UAV FDI alarm over: CAUSE, N s` (the alarm's length in flight time)."""
    return f"{PREFIX} alarm over: {cause or UNKNOWN_CAUSE}, {duration_s:.0f} s"[:TEXT_CHARS]


def estimate_text(name: str, value_pct: float, over: bool) -> str:
    """`UAV FDI: NAME V% over 2%` or `... under 2%` (name: the short one; V to 0.01 %, so
    that a value just under the threshold never reads as it)."""
    side = "over" if over else "under"
    value = round(value_pct, 2) + 0.0  # + 0.0: -0.001 reads 0.00, not -0.00
    return f"{PREFIX}: {name} {value:.2f}% {side} {DETECTION_THRESHOLD_PCT:g}%"[:TEXT_CHARS]


@dataclass(frozen=True)
class GroundText:
    """One STATUSTEXT: its MAV_SEVERITY and its text (at most TEXT_CHARS)."""

    severity: int
    text: str
    key: str = ""  # what it reports: "alarm", or an estimate's short name


@dataclass
class Episode:
    """An alarm or an estimate over the threshold, as told: on since onset_s, off since
    off_s (None while on) [s, flight time]; an alarm's cause at the onset."""

    onset_s: float
    cause: str = ""
    off_s: float | None = None

    def ended(self, flight_s: float, on: bool, hold_s: float) -> bool:
        """Whether, on or not at flight_s [s], the episode has now been off for hold_s."""
        if on:
            self.off_s = None
        elif self.off_s is None:
            self.off_s = flight_s
        return not on and flight_s - self.off_s >= hold_s


@dataclass
class GroundTexts:
    """The STATUSTEXTs of a flight's estimates and alarms (module docstring): events in,
    texts out through `due`."""

    min_interval_s: float  # least wall time between two texts [s]
    hold_s: float  # flight time an alarm or estimate is off before its end is said [s]
    said_s: float | None = None  # wall time of the last text [s]
    waiting: list[GroundText] = field(default_factory=list)
    dropped: int = 0  # texts not sent: more than MAX_WAITING were waiting
    over: dict[str, Episode] = field(default_factory=dict)  # estimates told over, by name
    alarm_on: Episode | None = None  # the alarm told on; None while none is

    def estimates(self, flight_s: float, names: Sequence[str],
                  values_pct: Sequence[float]) -> None:
        """The estimates [%] at flight_s [s]: a text for each reaching the threshold, and
        for each back under it for hold_s."""
        for name, value in named_values(names, values_pct):
            over = value >= DETECTION_THRESHOLD_PCT
            episode = self.over.get(name)
            if over and episode is None:
                self.over[name] = Episode(flight_s)
                self._wait(GroundText(ALARM_SEVERITY, estimate_text(name, value, True), name))
            elif episode is not None and episode.ended(flight_s, over, self.hold_s):
                del self.over[name]
                waiting = [text for text in self.waiting if text.key == name]
                if waiting:  # back under before its text left: withdrawn
                    self.waiting.remove(waiting[0])
                else:
                    self._wait(GroundText(END_SEVERITY, estimate_text(name, value, False),
                                          name))

    def alarm(self, flight_s: float, combined_alarm: bool, cause: str,
              tests: Sequence[str]) -> None:
        """The detector's combined alarm at flight_s [s], its cause and raising tests."""
        episode = self.alarm_on
        if combined_alarm and episode is None:
            self.alarm_on = Episode(flight_s, cause)
            self._wait(GroundText(ALARM_SEVERITY, alarm_onset_text(cause, tests), "alarm"))
        elif episode is not None and episode.ended(flight_s, combined_alarm, self.hold_s):
            self.alarm_on = None
            self._wait(GroundText(END_SEVERITY, alarm_end_text(
                episode.cause, episode.off_s - episode.onset_s), "alarm"))

    def due(self, now_s: float) -> GroundText | None:
        """The next text to send at wall time now_s [s], if the interval allows one."""
        if not self.waiting or (self.said_s is not None
                                and now_s - self.said_s < self.min_interval_s):
            return None
        self.said_s = now_s
        return self.waiting.pop(0)

    def _wait(self, text: GroundText) -> None:
        if len(self.waiting) < MAX_WAITING:
            self.waiting.append(text)
        else:
            self.dropped += 1
