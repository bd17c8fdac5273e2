"""Start ROS nodes and tools as processes the way a user would, and always stop them."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import time
from collections.abc import Iterable, Sequence
from pathlib import Path

STOP_TIMEOUT_S = 10.0


class RosProcess:
    """A command in a process group of its own, its output in a log file.

    stop() sends SIGINT to the whole group (as Ctrl-C would), then SIGKILL to whatever is
    left after STOP_TIMEOUT_S; it is safe to call more than once.
    """

    def __init__(self, argv: Sequence[str], log_path: Path) -> None:
        self.argv = list(argv)
        self.log_path = log_path
        self._log = open(log_path, "w")  # noqa: SIM115 (closed in stop())
        self.process = subprocess.Popen(
            self.argv, stdout=self._log, stderr=subprocess.STDOUT, start_new_session=True
        )

    @property
    def pid(self) -> int:
        return self.process.pid

    def running(self) -> bool:
        return self.process.poll() is None

    def output(self) -> str:
        """Everything the process printed so far."""
        return self.log_path.read_text()

    def wait(self, timeout_s: float) -> int:
        """Exit status, waiting up to timeout_s (raises subprocess.TimeoutExpired)."""
        return self.process.wait(timeout=timeout_s)

    def stop(self, sig: int = signal.SIGINT) -> int:
        """Signal the process group, wait, kill what remains; the exit status of the process."""
        if self.running():
            _signal_group(self.pid, sig)
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.process.wait(timeout=STOP_TIMEOUT_S)
        _signal_group(self.pid, signal.SIGKILL)  # children that outlived their parent
        status = self.process.wait()
        self._log.close()
        return status


def _signal_group(pgid: int, sig: int) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.killpg(pgid, sig)


def ros2_run_argv(
    package: str, executable: str, ros_args: Iterable[str] = (), arguments: Iterable[str] = ()
) -> list[str]:
    """The `ros2 run` command line of a node, with --ros-args when there are any."""
    argv = ["ros2", "run", package, executable, *arguments]
    ros_args = list(ros_args)
    return argv + (["--ros-args", *ros_args] if ros_args else [])


def wait_until(predicate, timeout_s: float, poll_s: float = 0.1) -> bool:
    """Poll predicate() until it is true or timeout_s passes; whether it became true."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(poll_s)
    return bool(predicate())
