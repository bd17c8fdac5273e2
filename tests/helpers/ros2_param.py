"""`ros2 param get/set` as a person types them, from a test: what they print."""

from __future__ import annotations

import subprocess


def param_set(node: str, name: str, value: str) -> str:
    """What `ros2 param set` prints (stdout and stderr), stripped."""
    result = subprocess.run(["ros2", "param", "set", node, name, value], capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    return (result.stdout + result.stderr).strip()


def param_get(node: str, name: str) -> str:
    """What `ros2 param get` prints, stripped."""
    result = subprocess.run(["ros2", "param", "get", node, name], capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()
