"""Residuals of simulated flights in calm air, each flight flown once per session."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pytest
from helpers.flights import calm, fly
from uav_fault_estimator.prediction import aircraft_predictor_factory
from uav_fault_estimator.residuals import ResidualGenerator, ResidualSample
from uav_sim.channels import PAPER_FAULT_NAMES
from uav_sim.scenario import SeededFault, default_scenario_path, load_scenario

# The default route in calm air for 90 s: 60 s straight, then the first turn.
FLIGHT_S = 90.0
TAU_A_S = 4.0
SETTLED_S = 3 * TAU_A_S  # the filter transient, excluded from every figure
SECANT_STEP_PCT = 5.0

ResidualFlight = Callable[[dict[str, float]], list[ResidualSample]]


@pytest.fixture(scope="session")
def residual_flight() -> ResidualFlight:
    """Residuals after the transient of a calm flight with faults [%] held from the start."""
    base = calm(load_scenario(default_scenario_path()), FLIGHT_S)
    factory = aircraft_predictor_factory()
    flown: dict[tuple, list[ResidualSample]] = {}

    def residuals(faults_pct: dict[str, float]) -> list[ResidualSample]:
        key = tuple(sorted(faults_pct.items()))
        if key not in flown:
            faults = tuple(SeededFault(name, 0.0, 0.0, value) for name, value in key)
            generator = ResidualGenerator(
                factory, PAPER_FAULT_NAMES, SECANT_STEP_PCT, TAU_A_S,
                sensitivity_period_s=0.5, recovery_s=SETTLED_S,
            )
            samples = [
                generator.update(s.time_s, s.state, s.controls, s.wind_filtered_ned_mps)
                for s in fly(dataclasses.replace(base, faults=faults))
            ]
            flown[key] = [s for s in samples if s is not None and s.time_s >= SETTLED_S]
        return flown[key]

    return residuals


def stacked(samples: list[ResidualSample], field: str) -> np.ndarray:
    """One field of every sample, stacked along a new first axis."""
    return np.array([getattr(sample, field) for sample in samples])
