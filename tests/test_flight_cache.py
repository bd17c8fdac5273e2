"""The flights the tests share (helpers/flight_cache.py): each flown once, by the first
process to ask; the others wait for it and read it back."""

from __future__ import annotations

import fcntl
import os
import pickle
import threading

import pytest
from helpers.flight_cache import PICKLE_PROTOCOL, FlightCache

CALLS: list[tuple[float, ...]] = []  # the arguments flown() computed, in this process


def counted(*arguments: float) -> dict[str, tuple[float, ...]]:
    """A stand-in flight that records its call."""
    CALLS.append(arguments)
    return {"flown": arguments}


@pytest.fixture
def calls() -> list[tuple[float, ...]]:
    CALLS.clear()
    return CALLS


@pytest.mark.timeout(10)
def test_a_flight_is_flown_once_and_read_back_after(tmp_path, calls):
    cache = FlightCache(tmp_path / "flights")
    first = cache.flown(counted, 1.0, 2.0)
    again = FlightCache(tmp_path / "flights").flown(counted, 1.0, 2.0)  # as another process
    other = cache.flown(counted, 1.0, 3.0)
    assert first == again == {"flown": (1.0, 2.0)} and other == {"flown": (1.0, 3.0)}
    assert calls == [(1.0, 2.0), (1.0, 3.0)]
    assert sorted(path.suffix for path in (tmp_path / "flights").iterdir()) == [
        ".lock", ".lock", ".pkl", ".pkl"]  # no temporary file left


@pytest.mark.timeout(10)
def test_a_process_asking_while_another_flies_waits_and_reads_its_flight(tmp_path, calls):
    """The entry's lock held here, as by a process flying it: a thread asking for the same
    flight waits (still waiting after 0.5 s), then returns what that process wrote, without
    flying it again."""
    cache = FlightCache(tmp_path)
    path = cache.path(counted, 4.0)
    asked: list[dict] = []
    with open(path.with_suffix(".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        waiting = threading.Thread(target=lambda: asked.append(cache.flown(counted, 4.0)))
        waiting.start()
        waiting.join(0.5)
        assert waiting.is_alive() and calls == []
        written = path.with_suffix(f".{os.getpid()}.tmp")
        written.write_bytes(pickle.dumps({"flown": "elsewhere"}, protocol=PICKLE_PROTOCOL))
        written.replace(path)
    waiting.join(5.0)
    assert asked == [{"flown": "elsewhere"}] and calls == []
