"""Match messages of several streams by their stamp, not by their arrival order."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass
class StampMatcher:
    """Collects one payload per stream for each stamp and releases complete sets in order.

    A set is released when every stream has delivered its stamp; older incomplete sets are
    dropped then (a message was lost) and counted. A stamp older than the newest released
    one means the source restarted: `add` reports it and the caller decides (reset).
    """

    streams: tuple[str, ...]
    pending: dict[int, dict[str, Any]] = field(default_factory=dict)
    last_released_ns: int | None = None
    dropped_sets: int = 0

    def reset(self) -> None:
        self.pending.clear()
        self.last_released_ns = None

    def is_backwards(self, stamp_ns: int) -> bool:
        """Whether a stamp lies at or before the newest released one (a restarted source)."""
        return self.last_released_ns is not None and stamp_ns <= self.last_released_ns

    def add(self, stream: str, stamp_ns: int, payload: Any) -> list[tuple[int, dict[str, Any]]]:
        """Store one message; return the sets completed by it, oldest first."""
        if stream not in self.streams:
            raise KeyError(f"unknown stream '{stream}', expected one of {self.streams}")
        entry = self.pending.setdefault(stamp_ns, {})
        entry[stream] = payload
        if len(entry) < len(self.streams):
            return []
        released = []
        for stamp in sorted(s for s in self.pending if s <= stamp_ns):
            candidate = self.pending.pop(stamp)
            if len(candidate) == len(self.streams):
                released.append((stamp, candidate))
            else:
                self.dropped_sets += 1
        self.last_released_ns = stamp_ns
        return released
