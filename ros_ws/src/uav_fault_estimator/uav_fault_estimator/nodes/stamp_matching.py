"""Match messages of several streams by their stamp, not by their arrival order."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any


@dataclass
class StampMatcher:
    """Collects one payload per stream for each stamp and releases complete sets in order.

    A set is released when every required stream has delivered its stamp and every optional
    one has too, or is not awaited (awaited(stream) False: nobody publishes it), or
    optional_wait newer stamps' required sets are complete (that optional message is late
    or lost: the set goes without it, and the message, should it come, is dropped and
    counted). Older sets whose required part never completed are dropped when a newer one
    is released, and counted. A required stamp older than the newest released one means
    the source restarted: `is_backwards` tells, and the caller decides (reset).
    """

    streams: tuple[str, ...]
    optional: tuple[str, ...] = ()
    awaited: Callable[[str], bool] = lambda stream: True
    optional_wait: int = 20
    pending: dict[int, dict[str, Any]] = field(default_factory=dict)
    last_released_ns: int | None = None
    dropped_sets: int = 0
    late_optional: int = 0

    def reset(self) -> None:
        self.pending.clear()
        self.last_released_ns = None

    def is_backwards(self, stamp_ns: int) -> bool:
        """Whether a stamp lies at or before the newest released one (a restarted source)."""
        return self.last_released_ns is not None and stamp_ns <= self.last_released_ns

    def _complete(self, entry: dict[str, Any]) -> bool:
        return all(stream in entry for stream in self.streams)

    def add(self, stream: str, stamp_ns: int, payload: Any) -> list[tuple[int, dict[str, Any]]]:
        """Store one message; return the sets it lets go, oldest first."""
        if stream not in self.streams + self.optional:
            raise KeyError(f"unknown stream '{stream}', expected one of "
                           f"{self.streams + self.optional}")
        if stream in self.optional and self.is_backwards(stamp_ns):
            self.late_optional += 1  # its set went without it
            return []
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
            newer = len(complete) - 1 - complete.index(stamp)
            if newer < self.optional_wait and any(
                    o not in entry and self.awaited(o) for o in self.optional):
                break  # its optional message may still come
            released.append((stamp, self.pending.pop(stamp)))
            self.last_released_ns = stamp
        return released
