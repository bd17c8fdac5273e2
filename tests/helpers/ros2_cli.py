"""Running the project's `ros2` command from a test, as a person types it."""

from __future__ import annotations

import os
import signal
import subprocess
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor

# Commands run_cli_all runs at once. Most of a graph query is waiting for discovery to
# settle (about 1.6 s), not CPU; more than three at once on two loaded cores would slow
# their start-up enough to crowd their --spin-time.
CONCURRENT_COMMANDS = 3
# --spin-time of param_set and param_get: the longest the command may look for a live node
# (it goes on as soon as it finds it); its 2 s default is too short on two loaded cores.
FIND_NODE_S = "30"
STACKS_WAIT_S = 10.0  # for a command stuck past its timeout to print its stacks [s]


def run_cli(*args: str, timeout_s: float = 60) -> subprocess.CompletedProcess:
    """`ros2 ARGS...` to its end; its status, stdout and stderr (text). A command still
    running after timeout_s fails the test with every thread's Python stack (SIGABRT under
    PYTHONFAULTHANDLER), so that a rare hang says where it was."""
    argv = ["ros2", *args]
    environment = {**os.environ, "PYTHONFAULTHANDLER": "1"}
    with subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          env=environment) as process:
        try:
            stdout, stderr = process.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            process.send_signal(signal.SIGABRT)
            try:
                _, stacks = process.communicate(timeout=STACKS_WAIT_S)
            except subprocess.TimeoutExpired:
                process.kill()
                _, stacks = process.communicate()
            raise AssertionError(f"{' '.join(argv)} still running after {timeout_s:g} s; "
                                 f"its stacks:\n{stacks}") from None
    return subprocess.CompletedProcess(argv, process.returncode, stdout, stderr)


def run_cli_all(*commands: Sequence[str],
                timeout_s: float = 60) -> list[subprocess.CompletedProcess]:
    """run_cli of each command (its arguments), several at a time: for queries that do not
    depend on each other's effects. The results in the commands' order."""
    with ThreadPoolExecutor(max_workers=CONCURRENT_COMMANDS) as pool:
        return list(pool.map(lambda args: run_cli(*args, timeout_s=timeout_s), commands))


def param_set(node: str, name: str, value: str) -> str:
    """What `ros2 param set` prints (stdout and stderr), stripped."""
    result = run_cli("param", "set", node, name, value, "--spin-time", FIND_NODE_S)
    assert result.returncode == 0, result.stderr
    return (result.stdout + result.stderr).strip()


def param_get(node: str, name: str) -> str:
    """What `ros2 param get` prints, stripped."""
    result = run_cli("param", "get", node, name, "--spin-time", FIND_NODE_S)
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()
