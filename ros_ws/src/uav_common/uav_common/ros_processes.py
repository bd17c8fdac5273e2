"""Start ROS nodes and tools as processes the way a user would, and always stop them. No
rclpy here: the demo (demo_run.py) and the tests share this module; a run's ROS domain is
uav_common.ros_domain's.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path

STOP_TIMEOUT_S = 10.0


class RosProcess:
    """A command in a process group of its own, its output in a log file.

    stop() sends SIGINT to the whole group (as Ctrl-C would), then SIGKILL to whatever is
    left after STOP_TIMEOUT_S; it is safe to call more than once.
    """

    def __init__(self, argv: Sequence[str], log_path: Path,
                 env: Mapping[str, str] | None = None) -> None:
        self.argv = list(argv)
        self.log_path = log_path
        self._log = open(log_path, "w")  # noqa: SIM115 (closed in stop())
        self.process = subprocess.Popen(
            self.argv, stdout=self._log, stderr=subprocess.STDOUT, start_new_session=True,
            env=None if env is None else dict(env),
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

    def send_signal(self, sig: int) -> None:
        """Send sig to the process's group if the process still runs."""
        if self.running():
            _signal_group(self.pid, sig)

    def stop(self, sig: int = signal.SIGINT) -> int:
        """Signal the process group, wait, kill what remains; the exit status of the process."""
        return stop_all([self], sig)[0]

    def _finish(self) -> int:
        _signal_group(self.pid, signal.SIGKILL)  # children that outlived their parent
        status = self.process.wait()
        self._log.close()
        return status


def stop_all(processes: Sequence[RosProcess], sig: int = signal.SIGINT,
             timeout_s: float = STOP_TIMEOUT_S) -> list[int]:
    """Signal every process group at once, wait up to timeout_s for all of them together,
    kill what remains; the exit statuses, in the order given. Safe to call more than once."""
    for process in processes:
        process.send_signal(sig)
    deadline = time.monotonic() + timeout_s
    for process in processes:
        with contextlib.suppress(subprocess.TimeoutExpired):
            process.process.wait(timeout=max(0.0, deadline - time.monotonic()))
    return [process._finish() for process in processes]


def _signal_group(pgid: int, sig: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pgid, sig)


def ros2_run_argv(
    package: str, executable: str, ros_args: Iterable[str] = (), arguments: Iterable[str] = ()
) -> list[str]:
    """The `ros2 run` command line of a node, with --ros-args when there are any."""
    argv = ["ros2", "run", package, executable, *arguments]
    ros_args = list(ros_args)
    return argv + (["--ros-args", *ros_args] if ros_args else [])


def fast_flight_ros_args(scenario: Path | str, subscribers: int) -> list[str]:
    """sim_node's --ros-args to fly the scenario as fast as its subscribers keep up, once
    `state` has this many subscriptions (its fast mode: nothing is lost)."""
    return ["-p", f"scenario:={scenario}", "-p", "real_time_factor:=0.0",
            "-p", f"wait_for_subscribers:={subscribers}"]


# The graph's nodes other than sim_node run on its /clock (simulation time).
SIM_TIME_ROS_ARGS = ("-p", "use_sim_time:=true")
# A node whose output its starter writes to a log file (RosProcess, bringup.sh) writes no
# log file of its own: rcl's, under ROS_LOG_DIR, would be a second copy of that output.
NO_LOG_FILE_ROS_ARGS = ("--disable-external-lib-logs",)


def wait_until(predicate: Callable[[], object], timeout_s: float, poll_s: float = 0.1) -> bool:
    """Poll predicate() until it is true or timeout_s passes; whether it became true."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(poll_s)
    return bool(predicate())


def exit_status_text(status: int) -> str:
    """An exit status as a person reads it: `status 1`, `status -9 (killed by SIGKILL)`."""
    if status < 0:
        with contextlib.suppress(ValueError):
            return f"status {status} (killed by {signal.Signals(-status).name})"
    return f"status {status}"
