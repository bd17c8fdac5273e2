"""Parse what `ros2 topic echo` printed."""

from __future__ import annotations

from typing import Any

import yaml


def echo_documents(text: str) -> list[Any]:
    """The YAML documents of echo's output; WARNING lines (stderr merged in) left out."""
    lines = [line for line in text.splitlines() if not line.startswith("WARNING:")]
    documents = "\n".join(lines).split("\n---")
    return [yaml.safe_load(document) for document in documents if document.strip()]
