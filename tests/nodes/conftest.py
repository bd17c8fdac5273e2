"""Fixtures of the node tests: scenario files and a watching node that forgets its topics."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
import yaml
from uav_sim.scenario import default_scenario_path


@pytest.fixture
def short_scenario(tmp_path) -> Callable[..., Path]:
    """short_scenario(duration_s, **overrides): the default scenario cut short, as a file."""

    def write(duration_s: float, **overrides) -> Path:
        scenario = yaml.safe_load(default_scenario_path().read_text())
        scenario.update(duration_s=duration_s, **overrides)
        path = tmp_path / f"short_{len(list(tmp_path.glob('short_*')))}.yaml"
        path.write_text(yaml.safe_dump(scenario))
        return path

    return write


@pytest.fixture
def graph(ros_graph):
    yield ros_graph
    ros_graph.unsubscribe_all()
