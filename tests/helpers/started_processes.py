"""Processes a test or a module starts, stopped together when it ends."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from uav_common.ros_processes import RosProcess

StartProcess = Callable[[list[str], str], RosProcess]


@contextmanager
def started_processes(folder: Path) -> Iterator[StartProcess]:
    """start(argv, name) starts a command as a process logging into folder/<name>.log; every
    process started is stopped, the last first, when the block ends."""
    started: list[RosProcess] = []

    def start(argv: list[str], name: str) -> RosProcess:
        process = RosProcess(argv, folder / f"{name}.log")
        started.append(process)
        return process

    try:
        yield start
    finally:
        for process in reversed(started):
            process.stop()
