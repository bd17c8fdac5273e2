"""Running the project's `ros2` command from a test, as a person types it."""

from __future__ import annotations

import subprocess


def run_cli(*args: str, timeout_s: float = 60) -> subprocess.CompletedProcess:
    """`ros2 ARGS...` to its end; its status, stdout and stderr (text)."""
    return subprocess.run(["ros2", *args], capture_output=True, text=True, timeout=timeout_s)


def param_set(node: str, name: str, value: str) -> str:
    """What `ros2 param set` prints (stdout and stderr), stripped."""
    result = run_cli("param", "set", node, name, value)
    assert result.returncode == 0, result.stderr
    return (result.stdout + result.stderr).strip()


def param_get(node: str, name: str) -> str:
    """What `ros2 param get` prints, stripped."""
    result = run_cli("param", "get", node, name)
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()
