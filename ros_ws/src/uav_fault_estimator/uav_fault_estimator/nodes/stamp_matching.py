"""Match messages of several streams by their stamp, not by their arrival order; tell a
stray stamp from a restarted source (no ROS here)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

from uav_common.sample_grid import NANOSECONDS_PER_SECOND


class StampVerdict(Enum):
    """What to do with a message, by its stamp (StampGuard.check)."""

    ACCEPT = "accept"    # in order
    STRAY = "stray"      # drop it, and nothing else
    RESTART = "restart"  # the source restarted: reset, then take this message as the first


@dataclass
class StampGuard:
    """Stamps of a stream should rise. A stamp not newer than the newest accepted one (a
    duplicate, one going backwards) or more than max_ahead_s past it is a stray: dropped,
    alone. Only when confirm_stamps such distinct stamps arrive with nothing accepted in
    between is the source taken as restarted (or jumped): the caller resets.

    A restart thus loses its first confirm_stamps - 1 stamps (0.2 s at 20 Hz), and a single
    bad stamp loses nothing but itself.
    """

    confirm_stamps: int = 5
    # Sensors every 0.05 s, residuals every 0.5 s: a jump of more than 2 s is no stream's
    # next message. (Accepting one that is, say, 7 s ahead would make the real stream behind
    # it look like strays until it counts as a restart: measured in scripts/soak.py.) A
    # source silent for longer than this comes back as a restart.
    max_ahead_s: float = 2.0
    newest_ns: int | None = None
    strays: set[int] = field(default_factory=set)

    def in_order(self, stamp_ns: int) -> bool:
        """Whether the stamp is newer than the newest accepted one, and not too far ahead."""
        newest = self.newest_ns
        return newest is None or (
            newest < stamp_ns <= newest + self.max_ahead_s * NANOSECONDS_PER_SECOND)

    def check(self, stamp_ns: int) -> StampVerdict:
        """Classify a stamp against the newest accepted one (`accept` records that)."""
        if self.in_order(stamp_ns):
            self.strays.clear()
            return StampVerdict.ACCEPT
        self.strays.add(stamp_ns)
        if len(self.strays) < self.confirm_stamps:
            return StampVerdict.STRAY
        self.reset()
        return StampVerdict.RESTART

    def accept(self, stamp_ns: int) -> None:
        """The stream's newest stamp is now stamp_ns."""
        self.newest_ns = stamp_ns

    def reset(self) -> None:
        self.newest_ns = None
        self.strays.clear()


@dataclass
class StampMatcher:
    """Collects one payload per stream for each stamp and releases complete sets in order.

    A set is released when every required stream has delivered its stamp and every optional
    one has too, or is not waited for, or optional_wait newer stamps' required sets are
    complete (that optional message is late or lost: the set goes without it, and the
    message, should it come, is dropped and counted). An optional stream is waited for while
    it has a publisher (awaited(stream)) and, once heard from, after its publisher has gone
    too: what it sent may still be queued here (a simulator that finished while this node
    was behind), until a set has gone without it for the full wait. A stream that has
    delivered a newer stamp is not waited for (one publisher's messages come in order: the
    one missing was lost, or dropped as a stray before a restart). Older sets whose
    required part never completed are dropped when a newer one is released, and counted.
    `guard` holds the newest released stamp: the caller asks it about each required message
    first (a stray is dropped, a restart resets).
    """

    streams: tuple[str, ...]
    optional: tuple[str, ...] = ()
    awaited: Callable[[str], bool] = lambda stream: True
    optional_wait: int = 20
    pending: dict[int, dict[str, Any]] = field(default_factory=dict)
    guard: StampGuard = field(default_factory=StampGuard)
    dropped_sets: int = 0
    late_optional: int = 0
    # the newest stamp of each optional stream heard from since the reset
    newest_optional_ns: dict[str, int] = field(default_factory=dict)
    abandoned: set[str] = field(default_factory=set)  # heard, gone, and waited out

    def reset(self) -> None:
        self.pending.clear()
        self.guard.reset()
        self.newest_optional_ns.clear()
        self.abandoned.clear()

    def _complete(self, entry: dict[str, Any]) -> bool:
        return all(stream in entry for stream in self.streams)

    def _waits_for(self, stream: str, stamp_ns: int) -> bool:
        """Whether the set of stamp_ns, missing this optional stream's message, holds for it."""
        if self.newest_optional_ns.get(stream, stamp_ns) > stamp_ns:
            return False
        if self.awaited(stream):
            return True
        return stream in self.newest_optional_ns and stream not in self.abandoned

    def add(self, stream: str, stamp_ns: int, payload: Any) -> list[tuple[int, dict[str, Any]]]:
        """Store one message; return the sets it lets go, oldest first."""
        if stream not in self.streams + self.optional:
            raise KeyError(f"unknown stream '{stream}', expected one of "
                           f"{self.streams + self.optional}")
        if stream in self.optional and not self.guard.in_order(stamp_ns):
            self.late_optional += 1  # its set went without it (or a stray stamp)
            return []
        if stream in self.optional:
            newest = self.newest_optional_ns.get(stream, stamp_ns)
            self.newest_optional_ns[stream] = max(stamp_ns, newest)
            self.abandoned.discard(stream)
        self.pending.setdefault(stamp_ns, {})[stream] = payload
        complete = sorted(stamp for stamp, entry in self.pending.items()
                          if self._complete(entry))
        released = []
        for stamp in sorted(s for s in self.pending if complete and s <= complete[-1]):
            entry = self.pending[stamp]
            if not self._complete(entry):
                del self.pending[stamp]
                self.dropped_sets += 1
                continue
            missing = [o for o in self.optional
                       if o not in entry and self._waits_for(o, stamp)]
            if missing and len(complete) - 1 - complete.index(stamp) < self.optional_wait:
                break  # its optional message may still come
            self.abandoned.update(o for o in missing if not self.awaited(o))
            released.append((stamp, self.pending.pop(stamp)))
            self.guard.accept(stamp)
        return released
