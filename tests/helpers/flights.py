"""Flying scenarios in the core Simulation, for the simulator and residual tests."""

from __future__ import annotations

import dataclasses

import numpy as np
from uav_sim.scenario import Scenario, SensorSuite
from uav_sim.simulation import Sample, Simulation


def fly(scenario: Scenario) -> list[Sample]:
    """Every sample of a scenario, the initial one first."""
    simulation = Simulation(scenario)
    samples = [simulation.sample()]
    while not simulation.finished:
        samples.append(simulation.step())
    return samples


def calm(scenario: Scenario, duration_s: float) -> Scenario:
    """The scenario without wind, turbulence, faults or sensor noise, cut to duration_s: the
    models' own accuracy, which sensor noise would hide."""
    wind = dataclasses.replace(
        scenario.wind, north_mps=0.0, east_mps=0.0, down_mps=0.0, turbulence="none"
    )
    return dataclasses.replace(scenario, wind=wind, faults=(), duration_s=duration_s,
                               sensors=SensorSuite(noise=False))


def column(samples: list[Sample], field: str, index: int | None = None) -> np.ndarray:
    """One field of every sample stacked; index picks one channel of an array field."""
    values = np.array([getattr(sample, field) for sample in samples])
    return values if index is None else values[:, index]
