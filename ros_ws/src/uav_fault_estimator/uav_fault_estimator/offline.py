"""The main job's chain without ROS: the core simulator, the residual generator and the
moving-horizon estimator on one scenario, with the nodes' parameters (their config YAML
unless given), every 0.5 s of simulation time as the nodes do. For tests, tuning and
benchmarks; metrics.py turns the result into metrics.json's figures."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from ament_index_python.packages import get_package_share_directory
from uav_sim.channels import FAULT_NAMES
from uav_sim.scenario import Scenario
from uav_sim.simulation import Simulation

from uav_fault_estimator.estimator_config import config_from_parameters
from uav_fault_estimator.metrics import EstimateSeries, SeededSeries
from uav_fault_estimator.mhe import MovingHorizonEstimator
from uav_fault_estimator.prediction import aircraft_predictor_factory
from uav_fault_estimator.residuals import RESIDUAL_CHANNELS, ResidualGenerator


def node_defaults(node: str) -> dict[str, Any]:
    """A node's parameters as its config/<node>.yaml sets them."""
    config_dir = Path(get_package_share_directory("uav_fault_estimator")) / "config"
    text = (config_dir / f"{node}.yaml").read_text()
    return dict(yaml.safe_load(text)["/**"]["ros__parameters"])


def residual_generator(parameters: Mapping[str, Any]) -> ResidualGenerator:
    """residual_node's generator from its parameters (config/residual_node.yaml's keys)."""
    p = parameters
    return ResidualGenerator(
        aircraft_predictor_factory(), p["fault_names"], p["secant_step_pct"], p["tau_a_s"],
        p["sensitivity_period_s"], p["recovery_s"], p["wind_error_step_mps"],
    )


def fly_and_estimate(
    scenario: Scenario,
    residual_overrides: Mapping[str, Any] | None = None,
    mhe_overrides: Mapping[str, Any] | None = None,
    true_wind: bool = False,
) -> tuple[EstimateSeries, SeededSeries]:
    """Fly the scenario and estimate its faults every update_period_s [s] of sim time.

    The estimator's parameters are mhe_node's defaults, then the scenario's `estimator`
    overrides, then mhe_overrides. Returns the published estimates (what mhe_node would
    publish; solve times are the estimator's update times) and the seeded faults sampled
    at the same stamps. true_wind: the models get the true wind (background and
    turbulence) instead of the filtered estimate, which no aircraft has: a bound on what
    better wind knowledge could give.
    """
    residual = {**node_defaults("residual_node"), **(residual_overrides or {})}
    mhe = {**node_defaults("mhe_node"), **scenario.estimator, **(mhe_overrides or {})}
    generator = residual_generator(residual)
    estimator = MovingHorizonEstimator(config_from_parameters(mhe, len(RESIDUAL_CHANNELS)))
    published = len(mhe["fault_names"])
    simulation = Simulation(scenario)
    period_s = float(residual["update_period_s"])
    stamps, values, statuses, times_ms, seeded = [], [], [], [], []
    sample = simulation.sample()
    while True:
        wind = sample.wind_ned_mps if true_wind else sample.wind_filtered_ned_mps
        result = generator.update(sample.time_s, sample.state, sample.controls, wind)
        on_grid = abs(sample.time_s / period_s - round(sample.time_s / period_s)) < 1e-9
        if result is not None and on_grid:
            estimate = estimator.update(result.residual, result.sensitivity, result.valid)
            stamps.append(sample.time_s)
            values.append(estimate.fault_pct[:published])
            statuses.append(int(estimate.status))
            times_ms.append(estimate.update_time_ms)
            seeded.append(sample.seeded_faults_pct)
        if simulation.finished:
            break
        sample = simulation.step()
    stamps_s = np.array(stamps)
    return (
        EstimateSeries(list(mhe["fault_names"]), stamps_s, np.array(values),
                       np.array(statuses), np.array(times_ms)),
        SeededSeries(list(FAULT_NAMES), stamps_s, np.array(seeded)),
    )
