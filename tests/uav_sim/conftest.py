"""Flights shared by the simulator tests (each flown once per session)."""

from __future__ import annotations

import pytest
from helpers.flights import fly
from uav_sim.scenario import Scenario, default_scenario_path, load_scenario
from uav_sim.simulation import Sample


@pytest.fixture(scope="session")
def default_scenario() -> Scenario:
    return load_scenario(default_scenario_path())


@pytest.fixture(scope="session")
def default_flight(default_scenario) -> list[Sample]:
    return fly(default_scenario)
