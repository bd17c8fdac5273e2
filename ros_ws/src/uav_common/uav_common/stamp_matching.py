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
    HOLD = "hold"        # far ahead: keep it until the next stamp tells a gap from a stray
    GAP = "gap"          # the stream resumed after a silence: take the held ones, then this
    RESTART = "restart"  # the source restarted: reset, then take this message as the first


@dataclass
class StampGuard:
    """One stream's stamps, each against that stream's own newest: they should rise.

    A stamp not newer than the newest (a duplicate, one going backwards) is a stray:
    dropped, alone; only confirm_stamps distinct ones in a row, with nothing in order
    between, are a restarted source (its clock went back: the caller resets). A stamp more
    than max_ahead_s past the newest is held: if the next one follows it (newer, within
    max_ahead_s), the stream resumed after a gap (a publisher that was silent, restarted or
    replaced, the flight going on): both are taken, nothing reset; otherwise the held one
    was a stray. Skew between streams does not matter: each is guarded on its own.

    A restart thus loses its first confirm_stamps - 1 stamps (0.2 s at 20 Hz), a gap
    nothing, and a single bad stamp nothing but itself.
    """

    confirm_stamps: int = 5
    # Sensors every 0.05 s, residuals every 0.5 s: a step of more than 2 s is no stream's
    # next message, but a gap in it or a bad stamp.
    max_ahead_s: float = 2.0
    newest_ns: int | None = None
    behind: set[int] = field(default_factory=set)  # distinct stray stamps since the newest
    held_ns: int | None = None  # a stamp far ahead, until the next one
    last_gap_ns: int = 0  # the silence before the last GAP: held stamp - newest before it

    def follows(self, stamp_ns: int, previous_ns: int | None) -> bool:
        """Whether stamp_ns is newer than previous_ns and not too far ahead of it."""
        return previous_ns is None or (
            previous_ns < stamp_ns <= previous_ns + self.max_ahead_s * NANOSECONDS_PER_SECOND)

    def check(self, stamp_ns: int) -> StampVerdict:
        """Classify a stamp against the stream's newest one, and record it when taken."""
        held, self.held_ns = self.held_ns, None
        if held is not None and self.follows(stamp_ns, held):
            self.last_gap_ns = held - (self.newest_ns if self.newest_ns is not None else held)
            self._take(stamp_ns)
            return StampVerdict.GAP
        if self.follows(stamp_ns, self.newest_ns):
            self._take(stamp_ns)
            return StampVerdict.ACCEPT
        if stamp_ns > self.newest_ns:
            self.held_ns = stamp_ns
            return StampVerdict.HOLD
        self.behind.add(stamp_ns)
        if len(self.behind) < self.confirm_stamps:
            return StampVerdict.STRAY
        self.reset()
        self._take(stamp_ns)
        return StampVerdict.RESTART

    def _take(self, stamp_ns: int) -> None:
        self.newest_ns = stamp_ns
        self.behind.clear()

    def reset(self) -> None:
        self.newest_ns = self.held_ns = None
        self.behind.clear()


@dataclass
class GuardedStream:
    """One stream's messages through its StampGuard: which to take, in order. A held
    message (far ahead) is kept here until the next one tells whether it began a gap."""

    guard: StampGuard = field(default_factory=StampGuard)
    held: tuple[int, Any] | None = None
    strays: int = 0  # messages dropped for their stamps

    def feed(self, stamp_ns: int, payload: Any) -> tuple[StampVerdict, list[tuple[int, Any]]]:
        """The verdict on this message and the (stamp, payload) pairs to take now, oldest
        first: after a GAP the held one too; after a RESTART the caller resets first."""
        verdict = self.guard.check(stamp_ns)
        held, self.held = self.held, None
        if verdict is StampVerdict.HOLD:
            self.held = (stamp_ns, payload)
        elif held is not None and verdict is not StampVerdict.GAP:
            self.strays += 1  # it was a stray far ahead
        if verdict in (StampVerdict.HOLD, StampVerdict.STRAY):
            self.strays += verdict is StampVerdict.STRAY
            return verdict, []
        return verdict, [*([held] if verdict is StampVerdict.GAP else []), (stamp_ns, payload)]

    def reset(self) -> None:
        self.guard.reset()
        self.held = None


@dataclass
class StampMatcher:
    """Collects one payload per stream for each stamp and releases complete sets in order.

    A set is released when every required stream has delivered its stamp and every optional
    one has too, or is not waited for, or optional_wait newer stamps' required sets are
    complete (that optional message is late or lost: the set goes without it, and the
    message, should it come, is dropped and counted). An optional stream is waited for while
    it may still send: it has a publisher (awaited(stream)), or it was heard from and what
    it sent may still be queued here (a simulator that finished while this node was
    behind). Once a set has gone without it after the full wait, it is not waited for
    again until it is heard from again: a stream that stopped (a silent publisher, a lost
    sensor) costs one wait, not one a set. A stream that has delivered a newer stamp is not
    waited for (one publisher's messages come in order: the one missing was lost). Older
    sets whose required part never completed are dropped when a newer one is released, and
    counted; beyond pending_max stamps held (a required stream that stopped, or one running
    further ahead than that), the oldest goes: released if complete, else dropped and
    counted. The caller guards each required stream's stamps (StampGuard) before adding.
    """

    streams: tuple[str, ...]
    optional: tuple[str, ...] = ()
    awaited: Callable[[str], bool] = lambda stream: True
    optional_wait: int = 20
    pending_max: int = 400  # 20 s of 20 Hz sensor samples
    pending: dict[int, dict[str, Any]] = field(default_factory=dict)
    released_ns: int | None = None  # the newest released set's stamp
    dropped_sets: int = 0
    late_optional: int = 0
    # the newest stamp of each optional stream heard from since the reset
    newest_optional_ns: dict[str, int] = field(default_factory=dict)
    abandoned: set[str] = field(default_factory=set)  # waited out, not heard from since

    def reset(self) -> None:
        self.pending.clear()
        self.released_ns = None
        self.newest_optional_ns.clear()
        self.abandoned.clear()

    def _complete(self, entry: dict[str, Any]) -> bool:
        return all(stream in entry for stream in self.streams)

    def _waits_for(self, stream: str, stamp_ns: int) -> bool:
        """Whether the set of stamp_ns, missing this optional stream's message, holds for it."""
        if self.newest_optional_ns.get(stream, stamp_ns) > stamp_ns or stream in self.abandoned:
            return False
        return self.awaited(stream) or stream in self.newest_optional_ns

    def add(self, stream: str, stamp_ns: int, payload: Any) -> list[tuple[int, dict[str, Any]]]:
        """Store one message; return the sets it lets go, oldest first."""
        if stream not in self.streams + self.optional:
            raise KeyError(f"unknown stream '{stream}', expected one of "
                           f"{self.streams + self.optional}")
        if stream in self.optional:
            self.abandoned.discard(stream)  # heard from again, if late: waited for again
            if self.released_ns is not None and stamp_ns <= self.released_ns:
                self.late_optional += 1  # its set went without it
                return []
            newest = self.newest_optional_ns.get(stream, stamp_ns)
            self.newest_optional_ns[stream] = max(stamp_ns, newest)
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
            self.abandoned.update(missing)
            released.append((stamp, self.pending.pop(stamp)))
            self.released_ns = stamp
        while len(self.pending) > self.pending_max:
            stamp = min(self.pending)
            entry = self.pending.pop(stamp)
            if self._complete(entry):
                released.append((stamp, entry))
                self.released_ns = stamp
            else:
                self.dropped_sets += 1
        return released
