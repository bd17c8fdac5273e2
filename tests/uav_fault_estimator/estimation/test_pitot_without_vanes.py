"""A pitot without vanes: the models fly the pitot's airspeed along the filtered wind's air
velocity, and the wind-error columns carry only the gusts across it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers.flights import calm, column, fly
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import PAPER_FAULT_NAMES
from uav_fault_estimator.estimation.prediction import aircraft_predictor_factory
from uav_fault_estimator.estimation.residuals import (
    RESIDUAL_CHANNELS,
    WIND_PITOT,
    ResidualGenerator,
    pitot_wind_ned_mps,
)
from uav_sim.scenario import default_scenario_path, load_scenario

LINEAR_X = RESIDUAL_CHANNELS.index("linear_x")
NORTH_ERROR = len(PAPER_FAULT_NAMES)  # the first wind-error column


@pytest.mark.timeout(30)
def test_the_pitot_wind_keeps_the_direction_and_gives_the_measured_airspeed():
    velocity, wind = np.array([20.0, 5.0, -1.0]), np.array([3.0, -2.0, 0.5])
    flown = pitot_wind_ned_mps(velocity, wind, 30.0)
    air, estimated_air = velocity - flown, velocity - wind
    assert np.linalg.norm(air) == pytest.approx(30.0)
    assert np.cross(air, estimated_air) == pytest.approx(np.zeros(3), abs=1e-12)
    assert air @ estimated_air > 0


@pytest.mark.timeout(300)
def test_a_tail_wind_error_moves_the_x_force_only_without_the_pitot():
    """On the calm northbound first leg (its first 40 s) a north wind error is a tail wind: flown on
    the filtered wind it takes airspeed, so drag, and moves the x force (+x); flown with the
    pitot, which measures that airspeed, it only turns the air velocity by its small
    crosswise part: its x force is below 2 % of the filtered wind's."""
    scenario = calm(load_scenario(default_scenario_path()), 40.0)
    scenario = dataclasses.replace(scenario, sensors=dataclasses.replace(
        scenario.sensors, vanes=False))
    predictors = aircraft_predictor_factory(load_vehicle(scenario.vehicle))
    generators = {name: ResidualGenerator(predictors, PAPER_FAULT_NAMES, 5.0, 4.0,
                                          sensitivity_period_s=0.5, recovery_s=12.0,
                                          wind_error_step_mps=1.0)
                  for name in ("pitot", "filtered wind")}
    flights: dict[str, list] = {name: [] for name in generators}
    for s in fly(scenario):
        for name, generator in generators.items():
            sample = generator.update(s.time_s, s.state, s.controls, s.wind_filtered_ned_mps,
                                      s.air_data if name == "pitot" else None)
            if sample is not None and sample.time_s >= 12.0:
                flights[name].append(sample)
    assert all(s.wind_source == WIND_PITOT for s in flights["pitot"])
    x_force = {}
    for name, flight in flights.items():
        x_force[name] = column(flight, "sensitivity")[:, LINEAR_X, NORTH_ERROR]
        print(f"{name}: x force per m/s of north wind error, mean "
              f"{x_force[name].mean():+.4f} m/s^2")
    assert np.all(x_force["filtered wind"] > 0)
    assert np.abs(x_force["pitot"]).max() < 0.02 * x_force["filtered wind"].min()
