"""Match messages of several streams by their stamp, not by their arrival order."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any


@dataclass
class StampMatcher:
    """Collects one payload per stream for each stamp and releases complete sets in order.

    A set is released when every required stream has delivered its stamp and every optional
    one has too, or is not awaited (awaited(stream) False: nobody publishes it), or a newer
    stamp's required set is complete (that optional message was lost). Older sets whose
    required part never completed are dropped then and counted. A stamp older than the
    newest released one means the source restarted: `add` reports it and the caller
    decides (reset).
    """

    streams: tuple[str, ...]
    optional: tuple[str, ...] = ()
    awaited: Callable[[str], bool] = lambda stream: True
    pending: dict[int, dict[str, Any]] = field(default_factory=dict)
    last_released_ns: int | None = None
    dropped_sets: int = 0

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
        self.pending.setdefault(stamp_ns, {})[stream] = payload
        complete = [stamp for stamp, entry in self.pending.items() if self._complete(entry)]
        if not complete:
            return []
        newest = max(complete)
        released = []
        for stamp in sorted(s for s in self.pending if s <= newest):
            entry = self.pending[stamp]
            if not self._complete(entry):
                del self.pending[stamp]
                self.dropped_sets += 1
                continue
            if stamp == newest and any(o not in entry and self.awaited(o)
                                       for o in self.optional):
                break  # its optional message may still come
            released.append((stamp, self.pending.pop(stamp)))
            self.last_released_ns = stamp
        return released
