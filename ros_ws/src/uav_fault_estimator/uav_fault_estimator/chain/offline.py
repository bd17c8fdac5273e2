"""The main job's chain without ROS: the core simulator, the residual generator and the
moving-horizon estimator on one scenario, with the nodes' settings (their defaults unless
given; the scenario's vehicle), every 0.5 s of simulation time as the nodes do. For tests,
tuning and benchmarks; metrics.py turns the result into metrics.json's figures."""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from uav_aircraft.flown_aircraft import NOMINAL, FlownAircraft
from uav_aircraft.vehicles import DEFAULT_VEHICLE
from uav_common.channels import AIRSPEED_INDEX, FAULT_NAMES
from uav_common.sample_grid import on_grid
from uav_common.settings import settings_from
from uav_sim.scenario import Scenario, load_scenario, vehicle_scenario_path
from uav_sim.simulation import SENSOR_RATE_HZ, Simulation

from uav_fault_estimator.campaigns.campaign import Campaign
from uav_fault_estimator.detection.detector import DetectorFlight
from uav_fault_estimator.estimation.estimator_settings import (
    EstimatorSettings,
    sensor_overrides,
)
from uav_fault_estimator.estimation.estimator_step import EstimatorStep, ResidualInput
from uav_fault_estimator.estimation.model_calibration import SensorFlight
from uav_fault_estimator.estimation.noise_model import without_wind_errors
from uav_fault_estimator.estimation.prediction import residual_sampler
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.estimation.residuals import WIND_PITOT, ResidualSample
from uav_fault_estimator.reporting.metrics import EstimateSeries, SeededSeries


def fly_and_estimate(
    scenario: Scenario,
    residual: ResidualSettings | None = None,
    estimator: EstimatorSettings | None = None,
    true_wind: bool = False,
    model: FlownAircraft = NOMINAL,
) -> tuple[EstimateSeries, SeededSeries]:
    """Fly the scenario and estimate its faults every update_period_s [s] of sim time.

    The residual generator's settings are `residual` (default: residual_node's, for the
    scenario's vehicle), the estimator's `estimator` (default: mhe_node's, for the
    scenario's vehicle and with the scenario's `estimator` overrides, of which mhe_node's
    own parameters, such as qos, have no part here, and with what its sensors call for,
    estimator_settings.sensor_overrides). Returns the published estimates
    (what mhe_node would publish; solve times are the estimator's update times) and the
    seeded faults sampled at the same stamps, with the synthetic air data's flow-angle
    errors against the simulator's truth where mhe_node publishes it. The models fly the
    air data where the aircraft has it, as residual_node does. true_wind: the models get
    the true wind (background and turbulence) instead, which no aircraft has: a bound on
    what better wind knowledge could give. model: the aircraft the models evaluate (a model
    calibration's), as residual_node's model_calibration_file gives it.
    """
    sampler = residual_sampler(residual or ResidualSettings(vehicle=scenario.vehicle), model)
    step = EstimatorStep(estimator or scenario_estimator_settings(scenario))
    simulation = Simulation(scenario)
    stamps, values, statuses, times_ms, cpu_ms, seeded = [], [], [], [], [], []
    flow_angle_errors = []
    sample = simulation.sample()
    while True:
        wind = sample.wind_ned_mps if true_wind else sample.wind_filtered_ned_mps
        result = sampler.update(sample.time_s, sample.state, sample.controls, wind,
                                None if true_wind else sample.air_data)
        if result is not None:
            estimate = step.update(step_input(result, sampler.generator.column_names))
            stamps.append(sample.time_s)
            values.append(estimate.published_pct)
            statuses.append(int(estimate.estimate.status))
            times_ms.append(estimate.estimate.update_time_ms)
            cpu_ms.append(estimate.estimate.update_cpu_ms)
            seeded.append(sample.seeded_faults_pct)
            air_data = estimate.air_data
            flow_angle_errors.append(
                [math.nan, math.nan] if air_data is None else
                [air_data.angle_of_attack_rad, air_data.sideslip_rad] - sample.true_air_data[1:])
        if simulation.finished:
            break
        sample = simulation.step()
    stamps_s = np.array(stamps)
    return (
        EstimateSeries(step.published_names, stamps_s, np.array(values),
                       np.array(statuses), np.array(times_ms), np.array(cpu_ms),
                       step.config.solver.method, np.array(flow_angle_errors).reshape(-1, 2)),
        SeededSeries(list(FAULT_NAMES), stamps_s, np.array(seeded)),
    )


def scenario_estimator_settings(scenario: Scenario) -> EstimatorSettings:
    """mhe_node's settings for the scenario: its vehicle, what its sensors call for
    (estimator_settings.sensor_overrides), then its `estimator` overrides."""
    sensors = scenario.sensors
    return settings_from(EstimatorSettings, {
        "vehicle": scenario.vehicle, **sensor_overrides(sensors.air_data, sensors.vanes),
        **scenario.estimator})


def step_input(sample: ResidualSample, column_names: Sequence[str]) -> ResidualInput:
    """A residual sample as the estimator step takes it (what residual_node publishes of
    it), its columns named column_names."""
    return ResidualInput(sample.time_s, sample.residual, sample.valid, sample.sensitivity,
                         column_names, sample.wind_source, sample.tau_a_s,
                         sample.wind_flown_ned_mps, sample.air_velocity_body_mps,
                         sample.attitude_rad)


class GridFlight(NamedTuple):
    """A simulated flight every period_s: times_s (K,) [s], states (K, 14), controls (K, 7),
    seeded faults (K, 7) [%], in uav_common.channels order, the measured true airspeed
    (K,) [m/s] (NaN without air data) and the autopilot's setpoints (K, 3) (SETPOINT_FIELDS
    order)."""

    times_s: np.ndarray
    states: np.ndarray
    controls: np.ndarray
    seeded_pct: np.ndarray
    airspeed_mps: np.ndarray
    setpoints: np.ndarray

    @property
    def detector_flight(self) -> DetectorFlight:
        """What the detector takes of it."""
        return DetectorFlight(self.times_s, self.states, self.controls, self.airspeed_mps,
                              self.setpoints)


def fly_on_grid(scenario: Scenario, period_s: float) -> GridFlight:
    """The scenario's samples every period_s [s] of simulation time (a multiple of the
    sensor period)."""
    simulation = Simulation(scenario)
    every = round(period_s / simulation.period_s)
    if every < 1 or not on_grid(period_s, simulation.period_s):
        raise ValueError(f"{period_s} s is not a multiple of the sensor period "
                         f"{simulation.period_s} s")
    samples = [simulation.sample()]
    while not simulation.finished:
        sample = simulation.step()
        if simulation.sample_count % every == 0:
            samples.append(sample)
    return GridFlight(np.array([s.time_s for s in samples]), np.array([s.state for s in samples]),
                      np.array([s.controls for s in samples]),
                      np.array([s.seeded_faults_pct for s in samples]),
                      np.array([math.nan if s.air_data is None else s.air_data[AIRSPEED_INDEX]
                                for s in samples]),
                      np.array([s.setpoints for s in samples]))


def fly_on_grid_each(campaign: Campaign, scenarios: Sequence[Scenario],
                     period_s: float) -> list[GridFlight]:
    """fly_on_grid of every scenario, as the campaign runs them (CampaignFailedError naming the
    flights that failed, once the others are done)."""
    return campaign.results(functools.partial(fly_on_grid, period_s=period_s), scenarios,
                            "flights")


def sensor_flight(scenario: Scenario, sensor_rate_hz: float = SENSOR_RATE_HZ) -> SensorFlight:
    """The scenario's samples at the sensor rate [Hz] as a recording of them gives them (what
    a model calibration reads)."""
    simulation = Simulation(scenario, sensor_rate_hz)
    samples = [simulation.sample()]
    while not simulation.finished:
        samples.append(simulation.step())
    return SensorFlight(
        f"scenario '{scenario.name}' seed {scenario.seed}",
        np.array([s.time_s for s in samples]), np.array([s.state for s in samples]),
        np.array([s.controls for s in samples]),
        np.array([s.wind_filtered_ned_mps for s in samples]),
        np.array([np.full(3, math.nan) if s.air_data is None else s.air_data
                  for s in samples]))


def fault_free_residuals(scenario: Scenario) -> np.ndarray:
    """The residuals (K, 6) residual_node would publish for the scenario with its default
    settings, on the update grid, where every row is valid; on a flight whose models fly a
    pitot without vanes, what they carry beyond the wind errors (noise_model.
    without_wind_errors), as the estimator sees them. (The faults' model copies are left
    out: y does not depend on them.)"""
    sampler = residual_sampler(ResidualSettings(vehicle=scenario.vehicle, fault_names=()))
    simulation = Simulation(scenario)
    sample, rows, wind_sensitivity, pitot = simulation.sample(), [], [], []
    while True:
        result = sampler.update(sample.time_s, sample.state, sample.controls,
                                sample.wind_filtered_ned_mps, sample.air_data)
        if result is not None and result.valid.all():
            rows.append(result.residual)
            wind_sensitivity.append(result.sensitivity)
            pitot.append(result.wind_source == WIND_PITOT)
        if simulation.finished:
            break
        sample = simulation.step()
    rows_array, pitot_rows = np.array(rows).reshape(-1, 6), np.array(pitot, dtype=bool)
    if pitot_rows.any():
        rows_array[pitot_rows] = without_wind_errors(rows_array[pitot_rows],
                                                     np.array(wind_sensitivity)[pitot_rows])
    return rows_array


def wind_variant(scenario: Scenario, seed: int, wind_direction_deg: float,
                 wind_speed_mps: float) -> Scenario:
    """The scenario with another turbulence seed and a horizontal background wind of
    wind_speed_mps [m/s] blowing towards wind_direction_deg [deg from north]."""
    direction = math.radians(wind_direction_deg)
    wind = dataclasses.replace(scenario.wind, north_mps=wind_speed_mps * math.cos(direction),
                               east_mps=wind_speed_mps * math.sin(direction))
    return dataclasses.replace(scenario, seed=seed, wind=wind)


def describe_flights(scenarios: Sequence[Scenario]) -> str:
    """One line for a calibration file's header: which flights of which scenario."""
    first = scenarios[0]
    return (f"'{first.name}' ({first.duration_s:g} s each, {first.wind.turbulence} "
            f"turbulence), seeds {', '.join(str(s.seed) for s in scenarios)}; winds "
            "north/east [m/s] "
            + ", ".join(f"{s.wind.north_mps:.2f}/{s.wind.east_mps:.2f}" for s in scenarios))


# The detector's calibration flights: fault_free_flights(CALIBRATION_FLIGHTS,
# CALIBRATION_FIRST_SEED); no study or test judges anything on these seeds.
CALIBRATION_FLIGHTS = 12
CALIBRATION_FIRST_SEED = 101


def fault_free_flights(count: int, first_seed: int, first_direction_deg: float = 0.0,
                       vehicle: str = DEFAULT_VEHICLE) -> list[Scenario]:
    """count variants of the vehicle's fault-free scenario (its default flight in its own
    turbulence and sensors): seeds from first_seed, background winds of 20-25 % of its
    airspeed (5.0-6.25 m/s at 25 m/s) towards directions 360/count degrees apart from
    first_direction_deg. The detector's calibration flights and, with other seeds, its
    held-out test flights."""
    base = load_scenario(vehicle_scenario_path(vehicle, "fault_free"))
    airspeed_mps = base.initial.airspeed_mps
    return [wind_variant(base, first_seed + i, first_direction_deg + 360.0 * i / count,
                         airspeed_mps * (20 + i % 6) / 100) for i in range(count)]
