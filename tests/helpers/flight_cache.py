"""Flights flown once per test run: a flight function's result (helpers.flights.fly, the
offline chain's) for its arguments, kept in a folder of the run's own and shared by every
test and every pytest-xdist worker process of the run that asks for the same flight.

The first process to ask flies it while holding the entry's file lock; the others wait on
the lock, then read the entry back. An entry appears whole or not at all (written to a
temporary file, then renamed), so a process killed while writing leaves no entry. The
folder is new with each run (conftest.flight_cache): no entry can outlive the code that
flew it, so the key is the call alone."""

from __future__ import annotations

import fcntl
import hashlib
import os
import pickle
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

PICKLE_PROTOCOL = 5
Result = TypeVar("Result")


class FlightCache:
    """Flight results in folder (made at the first entry)."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder

    def path(self, function: Callable[..., Any], *arguments: Any) -> Path:
        """The entry of function(*arguments): named by a hash of the call pickled (the
        function by reference, the arguments, e.g. a Scenario, by value)."""
        call = pickle.dumps((function, arguments), protocol=PICKLE_PROTOCOL)
        return self.folder / f"{hashlib.sha256(call).hexdigest()}.pkl"

    def flown(self, function: Callable[..., Result], *arguments: Any) -> Result:
        """function(*arguments) (a module-level function, picklable arguments and result):
        computed by the first process of the run to ask, read back by every later one."""
        path = self.path(function, *arguments)
        self.folder.mkdir(parents=True, exist_ok=True)
        with open(path.with_suffix(".lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file is closed
            if path.exists():
                return pickle.loads(path.read_bytes())
            result = function(*arguments)
            temporary = path.with_suffix(f".{os.getpid()}.tmp")
            temporary.write_bytes(pickle.dumps(result, protocol=PICKLE_PROTOCOL))
            temporary.replace(path)
            return result
