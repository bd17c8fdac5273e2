"""Whether the autopilot's link is alive, and each message's rate while it is.

The link is lost when nothing at all (heartbeat or stream) has come from the autopilot for
`lost_after_s`: a heartbeat late on a busy link, with the streams arriving, is no loss. A
loss is one line when it starts and one when it ends, with how long it lasted. Rates are
measured over the time the link was alive only: a gap between two of the autopilot's
messages longer than PAUSE_S (a heartbeat period and a half) is left out of the time they
are counted over, so a relay stopped for a while, or the node held up, does not read as a
slow stream. A window is judged once it holds `rate_window_s` of live time, and a message
too slow for the chain is said once (stream_rates.advice). No rclpy here: mavlink_node
feeds it wall times [s] and message types.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field

from uav_mavlink.stream_rates import advice, slow_messages

PAUSE_S = 1.5  # longer than the 1 Hz heartbeat's period: the link paused, not slow [s]


@dataclass(frozen=True)
class LinkLine:
    """A line for the log: its level (`warning` or `info`) and text."""

    level: str
    text: str


@dataclass
class LinkWatch:
    """The autopilot's link as heard: alive or lost, each message type's rate over the
    last judged window [Hz], the messages judged too slow."""

    lost_after_s: float  # nothing heard for this long: the link is lost [s]
    rate_window_s: float  # live time each rate is measured over [s]
    required_hz: Mapping[str, float]  # messages the chain needs, at these rates [Hz]
    optional_hz: Mapping[str, float]  # alternatives and extras, judged when they arrive [Hz]
    heard_s: float | None = None  # wall time the last message came [s]
    lost_s: float | None = None  # when the link was declared lost (None: alive) [s]
    losses: int = 0
    window: Counter[str] = field(default_factory=Counter)
    live_s: float = 0.0  # live time in the window [s]
    rates_hz: dict[str, float] = field(default_factory=dict)
    slow: list[str] = field(default_factory=list)
    advised: set[str] = field(default_factory=set)  # slow messages already said
    pending: list[LinkLine] = field(default_factory=list)

    @property
    def alive(self) -> bool:
        """Heard, and not lost since."""
        return self.heard_s is not None and self.lost_s is None

    def heard(self, now_s: float, kind: str) -> None:
        """A message of type kind from the autopilot at wall time now_s [s]."""
        if self.lost_s is not None:
            self.pending.append(LinkLine(
                "info", f"link back after {now_s - self.heard_s:.1f} s of silence"))
            self.lost_s = None
        elif self.heard_s is not None and now_s - self.heard_s <= PAUSE_S:
            self.live_s += now_s - self.heard_s
        self.heard_s = now_s
        self.window[kind] += 1

    def check(self, now_s: float, system: int, autopilot: str) -> list[LinkLine]:
        """The lines to say at wall time now_s [s], after every waiting message was heard:
        the link lost or back, and each message found too slow (with the setting of this
        autopilot, ArduPilot or PX4, that raises it)."""
        if self.alive and now_s - self.heard_s > self.lost_after_s:
            self.lost_s, self.losses = now_s, self.losses + 1
            self.pending.append(LinkLine("warning", (
                f"link lost: nothing from system {system} for {self.lost_after_s:g} s; its "
                "streams are missing until it returns (stream rates are not judged "
                "meanwhile)")))
            self._restart_window()
        if self.alive and self.live_s >= self.rate_window_s:
            self._judge(autopilot)
        lines, self.pending = self.pending, []
        return lines

    def _judge(self, autopilot: str) -> None:
        self.rates_hz = {kind: count / self.live_s for kind, count in self.window.items()}
        self.slow = slow_messages(self.rates_hz, self.required_hz, self.optional_hz)
        needed_hz = {**self.required_hz, **self.optional_hz}
        for message in self.slow:
            if message not in self.advised:
                self.advised.add(message)
                self.pending.append(LinkLine("warning", advice(
                    message, self.rates_hz.get(message, 0.0), round(needed_hz[message], 1),
                    autopilot)))
        self._restart_window()

    def _restart_window(self) -> None:
        self.window.clear()
        self.live_s = 0.0
