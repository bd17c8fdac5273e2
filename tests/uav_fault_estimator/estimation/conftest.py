"""Residuals of simulated flights in calm air, each flight flown once per session."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pytest
from helpers.flights import calm, fly
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import PAPER_FAULT_NAMES, STATE_CHANNELS
from uav_fault_estimator.estimation.prediction import aircraft_predictor_factory
from uav_fault_estimator.estimation.residuals import ResidualGenerator, ResidualSample
from uav_sim.scenario import SeededFault, default_scenario_path, load_scenario

# The default route in calm air for 90 s: 60 s straight, then the first turn.
FLIGHT_S = 90.0
TAU_A_S = 4.0
SETTLED_S = 3 * TAU_A_S  # the filter transient, excluded from every figure
SECANT_STEP_PCT = 5.0
ENGINE_SPEED = "engine_speed"

ResidualFlight = Callable[..., list[ResidualSample]]


@pytest.fixture(scope="session")
def residual_flight() -> ResidualFlight:
    """Residuals after the transient of a calm flight with faults [%] held from the start;
    with wind-error columns in S when wind_error_step_mps > 0; without the engine speed
    (NaN in every state, the models turning the propeller at its steady speed) when
    engine_speed_measured is False."""
    base = calm(load_scenario(default_scenario_path()), FLIGHT_S)
    vehicle = load_vehicle(base.vehicle)
    flown: dict[tuple, list[ResidualSample]] = {}

    def residuals(faults_pct: dict[str, float], wind_error_step_mps: float = 0.0,
                  engine_speed_measured: bool = True) -> list[ResidualSample]:
        key = (tuple(sorted(faults_pct.items())), wind_error_step_mps, engine_speed_measured)
        if key not in flown:
            faults = tuple(SeededFault(name, 0.0, 0.0, value) for name, value in key[0])
            generator = ResidualGenerator(
                aircraft_predictor_factory(vehicle,
                                           steady_engine_speed=not engine_speed_measured),
                PAPER_FAULT_NAMES, SECANT_STEP_PCT, TAU_A_S,
                sensitivity_period_s=0.5, recovery_s=SETTLED_S,
                wind_error_step_mps=wind_error_step_mps,
                unmeasured=frozenset() if engine_speed_measured else frozenset({ENGINE_SPEED}),
            )
            samples = [
                generator.update(s.time_s, _without(s.state, key[2]), s.controls,
                                 s.wind_filtered_ned_mps)
                for s in fly(dataclasses.replace(base, faults=faults))
            ]
            flown[key] = [s for s in samples if s is not None and s.time_s >= SETTLED_S]
        return flown[key]

    return residuals


def _without(state: np.ndarray, engine_speed_measured: bool) -> np.ndarray:
    """The state as an aircraft that does (not) measure its engine speed gives it."""
    if engine_speed_measured:
        return state
    state = state.copy()
    state[STATE_CHANNELS.index(ENGINE_SPEED)] = np.nan
    return state
