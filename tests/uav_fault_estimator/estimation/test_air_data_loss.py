"""A 30 s loss of the air data: the models fly the 10 s filtered wind meanwhile
(residuals.py, per sample), and the estimator holds its estimate through the loss and
while F_a forgets it (noise_model.SuiteNoise). Through the core chain (offline.py); that
residual_node shows the fallback on /diagnostics is tests/nodes/test_residual_node.py's,
that mhe_node holds is tests/nodes/test_mhe_node.py's."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from uav_common.channels import AIR_DATA_CHANNELS
from uav_common.channels import DETECTION_THRESHOLD_PCT as THRESHOLD_PCT
from uav_fault_estimator.chain.offline import fly_and_estimate
from uav_fault_estimator.estimation.estimator_step import SETTLE_S
from uav_fault_estimator.estimation.noise_model import SuiteNoise, load_noise_calibration
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.estimation.residuals import WIND_AIR_DATA, WIND_FILTERED
from uav_fault_estimator.reporting.metrics import fault_metrics
from uav_fault_estimator.reporting.targets import DETECTED_WITHIN_S as DELAY_LIMIT_S
from uav_fault_estimator.reporting.targets import RMSE_SHARE
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import SensorDropout, default_scenario_path, load_scenario

# Between the fault onsets: the lift ramp is found, the left drag and lift steps have come,
# the right drag ramp starts at 210 s. (A loss over an onset: docs/results.md.)
LOSS_S = (180.0, 210.0)


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_the_estimates_stay_within_the_targets_through_a_30_s_air_data_loss():
    scenario = load_scenario(default_scenario_path())
    start_s, end_s = LOSS_S
    lost = tuple(SensorDropout(channel, start_s, end_s) for channel in AIR_DATA_CHANNELS)
    scenario = dataclasses.replace(scenario, sensor_dropouts=lost)
    faults, false_alarms = fault_metrics(*fly_and_estimate(scenario), SETTLE_S, THRESHOLD_PCT)
    for name, fault in faults.items():
        print(f"{name}: {fault}")
    assert false_alarms == []
    for name, fault in faults.items():
        magnitude_pct = fault["seeded_final_pct"]
        assert fault["rmse_pct"] <= RMSE_SHARE * magnitude_pct, name
        assert fault["detection_delay_s"] <= DELAY_LIMIT_S, name


@pytest.mark.timeout(30)
def test_the_estimate_is_held_from_the_loss_until_f_a_has_forgotten_it():
    calibration = load_noise_calibration()
    noise = SuiteNoise(calibration, variance_factor=2.0)
    tau_a_s = 4.0  # the residuals' F_a: held for 3 tau_a = 12 s after the air data is back
    air, filtered = (calibration.q_diag(source, 2.0) for source in (WIND_AIR_DATA,
                                                                     WIND_FILTERED))
    # no air data yet (an aircraft without it, or before its first sample): filtered Q
    assert np.array_equal(noise.weigh(5.0, WIND_FILTERED, tau_a_s), filtered)
    assert np.array_equal(noise.weigh(10.0, WIND_AIR_DATA, tau_a_s), air)
    assert noise.weigh(20.0, WIND_FILTERED, tau_a_s) is None      # lost after being flown
    assert noise.weigh(31.5, WIND_AIR_DATA, tau_a_s) is None      # back, F_a still settling
    assert np.array_equal(noise.weigh(32.0, WIND_AIR_DATA, tau_a_s), air)
    # a residual filter twice as slow holds twice as long
    assert noise.weigh(35.0, WIND_FILTERED, tau_a_s) is None
    assert noise.weigh(50.0, WIND_AIR_DATA, 2 * tau_a_s) is None
    assert np.array_equal(noise.weigh(59.0, WIND_AIR_DATA, 2 * tau_a_s), air)
    noise.reset()
    assert np.array_equal(noise.weigh(60.0, WIND_FILTERED, tau_a_s), filtered)


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_a_fault_starting_during_the_loss_is_found_when_the_hold_ends():
    """Air data lost 90-120 s, over the left drag step of 25 % at 110 s: no false alarm
    (weighting the filtered-wind samples gave two), and the step found when the hold ends
    (120 + 12 s), 21.5 s after it came instead of 1.5 s: the price of not estimating from
    the filtered wind."""
    scenario = load_scenario(default_scenario_path())
    lost = tuple(SensorDropout(channel, 90.0, 120.0) for channel in AIR_DATA_CHANNELS)
    faults, false_alarms = fault_metrics(
        *fly_and_estimate(dataclasses.replace(scenario, sensor_dropouts=lost)),
        SETTLE_S, THRESHOLD_PCT)
    for name, fault in faults.items():
        print(f"{name}: {fault}")
    assert false_alarms == []
    tau_a_s = ResidualSettings().tau_a_s
    hold_ends_s = 120.0 + SuiteNoise.HOLD_AFTER_TAU_A * tau_a_s
    delay_s = faults["left_wing_drag_increase"]["detection_delay_s"]
    assert hold_ends_s - 0.5 <= 110.0 + delay_s <= hold_ends_s + 3.0
    for fault in faults.values():
        assert abs(fault["estimate_final_pct"] - fault["seeded_final_pct"]) < 1.0


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_a_30_s_air_data_loss_in_fault_free_flights_not_tuned_on(campaign):
    """Fault-free flights of seeds the estimator was not tuned on, air data lost from 100
    to 130 s. Weighting the filtered-wind samples (their Q, times 10, or blended back
    to the air data's along F_a's memory after the loss) left estimates of 2.2-3.6 %
    (seeds 11 and 13); holding the estimate keeps every one under the 2 % threshold after
    the loss begins. (Before it, seed 15 reads 2.4 % at 20 s with or without a loss.)"""
    scenario = load_scenario(scenarios_dir() / "fault_free.yaml")
    lost = tuple(SensorDropout(channel, 100.0, 130.0) for channel in AIR_DATA_CHANNELS)
    seeds = range(11, 17)
    flights = campaign.results(fly_and_estimate, [
        dataclasses.replace(scenario, seed=seed, sensor_dropouts=lost) for seed in seeds],
        "air data loss flights")
    largest = {seed: float(estimates.values_pct[estimates.stamps_s >= 100.0].max())
               for seed, (estimates, _) in zip(seeds, flights, strict=True)}
    print("largest fault-free estimate from the loss on, per seed [%]:", largest)
    assert max(largest.values()) < THRESHOLD_PCT
