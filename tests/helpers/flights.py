"""Flying scenarios in the core Simulation, for the simulator and residual tests."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from uav_sim.scenario import Scenario, SensorSuite
from uav_sim.simulation import Sample, Simulation
from uav_sim.wind import GUST_RATE_RADPS


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


def turbulence_met(default_scenario: Scenario, flight: tuple[float, float, int]):
    """300 s of the default loop in from_wind turbulence at (altitude [m], wind [m/s],
    seed): the gusts the aircraft met (true
    wind less the background) in turbulence axes (u along the wind, v right, w down), every
    20 Hz sample after the first; and the body-axis gust rates [rad/s] with the largest
    difference between the rates the aircraft's rate derivatives see and body rate less gust."""
    altitude_m, wind_mps, seed = flight
    direction = math.atan2(3.0, 4.0)
    wind = dataclasses.replace(
        default_scenario.wind, north_mps=wind_mps * math.cos(direction),
        east_mps=wind_mps * math.sin(direction), turbulence="from_wind")
    scenario = dataclasses.replace(
        default_scenario, seed=seed, wind=wind, faults=(),
        initial=dataclasses.replace(default_scenario.initial, altitude_m=altitude_m))
    simulation = Simulation(scenario)
    background = np.array([wind.north_mps, wind.east_mps, wind.down_mps])
    gusts, rates, rate_mismatch = [], [], 0.0
    while not simulation.finished:
        gusts.append(simulation.step().wind_ned_mps - background)
        fdm = simulation.fdm
        rates.append([fdm[name] for name in GUST_RATE_RADPS])
        for axis, rate in zip("pqr", rates[-1], strict=True):
            rate_mismatch = max(rate_mismatch, abs(
                fdm[f"aero/{axis}-rate-rad_sec"] - fdm[f"velocities/{axis}-aero-rad_sec"]
                + rate))
    north, east, down = np.array(gusts).T
    c, s = math.cos(direction), math.sin(direction)
    uvw = np.column_stack([c * north + s * east, -s * north + c * east, down])
    return uvw, np.array(rates), rate_mismatch
