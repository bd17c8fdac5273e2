"""What the nodes say on /diagnostics, as a test reads it from the arrays it collected."""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus


def latest_status(diagnostics: list[DiagnosticArray], node: str) -> DiagnosticStatus | None:
    """The newest status named node (its fully qualified name), or None."""
    for array in reversed(diagnostics):
        for status in array.status:
            if status.name == node:
                return status
    return None


def latest_values(diagnostics: list[DiagnosticArray], node: str) -> dict[str, str]:
    """The newest status's values of node by key; empty when it has said nothing yet."""
    status = latest_status(diagnostics, node)
    return {item.key: item.value for item in status.values} if status else {}


def recorded_count(diagnostics: list[DiagnosticArray], topic: str,
                   recorder: str = "/recorder_node") -> int:
    """How many messages of topic the recorder has written, as it last said (0: none yet)."""
    return int(latest_values(diagnostics, recorder).get(topic, 0))
