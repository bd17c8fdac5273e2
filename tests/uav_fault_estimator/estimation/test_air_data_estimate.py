"""Synthetic air data without vanes: the flow angles of the models' air velocity corrected
by the estimator's wind errors, against what can be worked by hand and against the
simulator's truth on a turbulent flight."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from uav_aircraft.frames import ned_to_body
from uav_fault_estimator.chain.offline import scenario_estimator_settings, step_input
from uav_fault_estimator.estimation.air_data_estimate import estimate_air_data
from uav_fault_estimator.estimation.estimator_config import EstimatorConfig, FaultConfig
from uav_fault_estimator.estimation.estimator_step import EstimatorStep
from uav_fault_estimator.estimation.mhe import MovingHorizonEstimator
from uav_fault_estimator.estimation.prediction import residual_sampler
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_sim.scenario import default_scenario_path, load_scenario
from uav_sim.simulation import Simulation

ATTITUDE = np.array([0.2, 0.05, 1.0])  # roll, pitch, yaw [rad]
AIR_VELOCITY = np.array([24.0, 0.5, 1.5])  # body axes [m/s]


@pytest.mark.timeout(30)
def test_no_wind_error_gives_the_flown_flow_angles_and_wind():
    flown_wind = np.array([3.0, -4.0, 0.2])
    estimate = estimate_air_data(flown_wind, AIR_VELOCITY, ATTITUDE, np.zeros(3),
                                 np.zeros((3, 3)))
    assert estimate.true_airspeed_mps == pytest.approx(np.linalg.norm(AIR_VELOCITY))
    assert estimate.angle_of_attack_rad == pytest.approx(math.atan2(1.5, 24.0))
    assert estimate.sideslip_rad == pytest.approx(math.asin(0.5 / np.linalg.norm(AIR_VELOCITY)))
    assert estimate.wind_ned_mps == pytest.approx(flown_wind)
    assert estimate.angle_of_attack_std_rad == estimate.sideslip_std_rad == 0.0


@pytest.mark.timeout(30)
def test_an_updraft_error_raises_the_angle_of_attack_by_its_share_of_the_airspeed():
    """A wind error of 0.5 m/s against the body's z axis (an updraft the filtered wind
    missed) adds 0.5 m/s to the air velocity's w: alpha grows by about 0.5 / V, and the
    pitot keeps V; 0.1 m/s of deviation in it gives about 0.1 / V of alpha's."""
    to_ned = ned_to_body(*ATTITUDE).T
    error = to_ned @ np.array([0.0, 0.0, -0.5])
    covariance = 0.01 * np.outer(to_ned[:, 2], to_ned[:, 2])
    estimate = estimate_air_data(np.zeros(3), AIR_VELOCITY, ATTITUDE, error, covariance)
    airspeed = np.linalg.norm(AIR_VELOCITY)
    assert estimate.true_airspeed_mps == pytest.approx(airspeed)
    assert estimate.angle_of_attack_rad - math.atan2(1.5, 24.0) == pytest.approx(
        0.5 / airspeed, rel=0.05)
    assert estimate.angle_of_attack_std_rad == pytest.approx(0.1 / airspeed, rel=0.05)
    assert estimate.sideslip_std_rad < 0.01 * estimate.angle_of_attack_std_rad


@pytest.mark.timeout(30)
def test_the_newest_covariance_is_the_data_alone_when_the_samples_are_unlinked():
    """One column, a random walk so loose that the samples do not inform each other: the
    newest sample's variance is its data's, Q / s^2."""
    config = EstimatorConfig(horizon=5, q_diag=(4.0,) * 6, r_diag_pct2=(1e6,),
                             faults=[FaultConfig("f", "random_walk", {"sigma": 1e4})])
    estimator = MovingHorizonEstimator(config)
    s = np.zeros((6, 1))
    s[2, 0] = 2.0
    for _ in range(8):
        estimator.update(np.full(6, 1.0), s)
    assert estimator.newest_covariance([0]).shape == (1, 1)
    assert estimator.newest_covariance([0])[0, 0] == pytest.approx(1.0, rel=1e-3)


@pytest.mark.timeout(300)
def test_the_estimated_flow_angles_follow_the_truth_on_a_turbulent_flight():
    """The default flight's first 120 s without vanes, in the paper's turbulence: the
    synthetic angle of attack and sideslip within the targets (1.0 and 1.5 deg RMS against
    the simulator's), and the wind errors' correction no worse than the filtered wind's
    triangle alone; the stated deviations of the right size (the errors' RMS within a
    factor 3 of their RMS)."""
    scenario = load_scenario(default_scenario_path())
    scenario = dataclasses.replace(scenario, duration_s=120.0, faults=(),
                                   sensors=dataclasses.replace(scenario.sensors, vanes=False))
    sampler = residual_sampler(ResidualSettings())
    step = EstimatorStep(scenario_estimator_settings(scenario))
    simulation = Simulation(scenario)
    errors, triangle, deviations = [], [], []
    sample = simulation.sample()
    while not simulation.finished:
        result = sampler.update(sample.time_s, sample.state, sample.controls,
                                sample.wind_filtered_ned_mps, sample.air_data)
        if result is not None:
            air_data = step.update(step_input(result, sampler.generator.column_names)).air_data
            if air_data is not None and sample.time_s >= 20.0:
                truth = sample.true_air_data[1:]
                u, v, w = result.air_velocity_body_mps
                flown = np.array([math.atan2(w, u), math.asin(v / math.hypot(u, v, w))])
                errors.append([air_data.angle_of_attack_rad, air_data.sideslip_rad] - truth)
                triangle.append(flown - truth)
                deviations.append([air_data.angle_of_attack_std_rad, air_data.sideslip_std_rad])
        sample = simulation.step()
    rms = np.degrees(np.sqrt(np.mean(np.square(errors), axis=0)))
    triangle_rms = np.degrees(np.sqrt(np.mean(np.square(triangle), axis=0)))
    stated = np.degrees(np.sqrt(np.mean(np.square(deviations), axis=0)))
    print(f"{len(errors)} samples; alpha, beta RMS error {rms.round(2)} deg (the filtered "
          f"wind's triangle alone: {triangle_rms.round(2)} deg); stated deviation "
          f"{stated.round(2)} deg")
    assert len(errors) > 150
    assert rms[0] <= 1.0 and rms[1] <= 1.5
    assert np.all(rms <= triangle_rms)
    assert np.all(stated / 3 <= rms) and np.all(rms <= 3 * stated)
