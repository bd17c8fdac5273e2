"""Running the project's `ros2` command from a test."""

from __future__ import annotations

import subprocess


def run_cli(*args: str, timeout_s: float = 60) -> subprocess.CompletedProcess:
    """`ros2 ARGS...` to its end; its status, stdout and stderr (text)."""
    return subprocess.run(["ros2", *args], capture_output=True, text=True, timeout=timeout_s)
