"""The detector with its shipped calibration on flights it was not calibrated on.

- The shipped calibration is what scripts/calibrate_detector.py makes (12 fault-free
  flights, seeds 101-112): same flights, same file.
- False alarms: on 12 held-out fault-free flights (seeds 201-212, winds towards directions
  halfway between the calibration's) each self-tuning test's alarm rate per sample is within
  a factor of 3 of the designed P_FA (longitudinal_force's GLRT at most 3 times it: its
  statistic's tail on the calibration flights is heavier than on these, Weibull shape 0.79,
  and it alarmed on none of their samples), each fast test's exceedances per sample at most 3 times
  the probability its designed rate per hour gives, no template of the template test (the
  shipped ones, at the designed rate) alarms, and the combined alarm's rate is lower than
  the parameter test's, which its self-tuning part needs.
- Detection: in aileron_loss.yaml (90 % aileron effectiveness lost at 150 s, turbulence
  from the wind, noisy sensors) the combined alarm rises within 10 s of the onset and never
  before it.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np
import pytest
import yaml
from helpers.nested import assert_same_numbers
from helpers.repo import REPO_ROOT
from uav_fault_estimator.chain.offline import fault_free_flights, fly_on_grid, fly_on_grid_each
from uav_fault_estimator.detection.calibration import Calibration
from uav_fault_estimator.detection.calibration_file import read_calibration
from uav_fault_estimator.detection.calibration_fit import calibrate
from uav_fault_estimator.detection.change_detection import per_sample_probability
from uav_fault_estimator.detection.detector import DetectorFlight, run_detector
from uav_fault_estimator.detection.detector_settings import (
    DetectorSettings,
    learned_failures,
)
from uav_fault_estimator.detection.generators import SHIPPED_GENERATORS
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import load_scenario

P_FA = DetectorSettings().false_alarm_probability
FAST_PER_HOUR = DetectorSettings().fast_false_alarms_per_hour
TESTS = (*SHIPPED_GENERATORS, "parameters", *(f"fast_{name}" for name in SHIPPED_GENERATORS),
         "combined")
SELF_TUNING = slice(0, len(SHIPPED_GENERATORS) + 1)
FAST = slice(len(SHIPPED_GENERATORS) + 1, -1)
ONSET_S = 150.0  # aileron_loss.yaml
# aileron_loss.yaml flown to 20 s after its onset, not 300 s: the flight and the detector
# are causal, so its first 170 s are the 300 s flight's bit for bit, and the test reads
# nothing later than 10 s after the onset.
FAULT_FLIGHT_S = 170.0


@pytest.fixture(scope="module")
def calibration() -> Calibration:
    return read_calibration("")


def alarms(samples) -> np.ndarray:
    """(K, TESTS): each channel's GLRT alarm, the parameter alarm, each channel's fast test,
    the combined alarm, for the samples where every test is running (the windows full, the
    RLS settled)."""
    return np.array([[*s.alarm, s.parameter_alarm, *s.fast_alarm, s.combined_alarm]
                     for s in samples if np.isfinite(s.statistic).all()
                     and np.isfinite(s.fast_statistic).all()], dtype=bool)


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_the_shipped_calibration_is_what_the_command_makes(tmp_path):
    out = tmp_path / "calibration.yaml"
    subprocess.run([sys.executable, str(REPO_ROOT / "scripts/calibrate_detector.py"),
                    "--out", str(out)], check=True, timeout=170)
    shipped = REPO_ROOT / "ros_ws/src/uav_aircraft/aircraft/aerosonde/detector_calibration.yaml"
    assert_same_numbers(yaml.safe_load(out.read_text()), yaml.safe_load(shipped.read_text()))


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_false_alarm_rates_on_held_out_flights(calibration, campaign):
    scenarios = fault_free_flights(12, first_seed=201, first_direction_deg=15.0)
    flights = [flight.detector_flight for flight in fly_on_grid_each(
        campaign, scenarios, calibration.sample_period_s)]
    _, templates = learned_failures(DetectorSettings(), calibration)
    runs = [run_detector(calibration, flight, P_FA, templates=templates) for flight in flights]
    raised = np.vstack([alarms(samples) for samples in runs])
    rates = raised.mean(axis=0)
    print(f"designed P_FA {P_FA} per sample; {len(raised)} samples; measured: "
          + ", ".join(f"{name} {rate:.4f} ({count})" for name, rate, count
                      in zip(TESTS, rates, raised.sum(axis=0), strict=True)))
    for name, rate in zip(TESTS[SELF_TUNING], rates[SELF_TUNING], strict=True):
        assert rate <= 3 * P_FA, name
        assert name == "longitudinal_force" or rate >= P_FA / 3, name
    fast_probability = per_sample_probability(FAST_PER_HOUR, calibration.fast_window,
                                              calibration.sample_period_s)
    for name, rate in zip(TESTS[FAST], rates[FAST], strict=True):
        assert rate <= 3 * fast_probability, (name, fast_probability)
    template_alarms = sum(int(np.sum([s.template_alarm for s in samples])) for samples in runs)
    print(f"template test: {template_alarms} samples over a threshold")
    assert template_alarms == 0
    assert rates[-1] < rates[TESTS.index("parameters")]


@pytest.mark.timeout(120)
def test_the_aileron_fault_raises_the_combined_alarm_soon_after_onset(calibration):
    scenario = load_scenario(scenarios_dir() / "aileron_loss.yaml")
    assert [(f.name, f.start_s) for f in scenario.faults] == [
        ("aileron_effectiveness_loss", ONSET_S)]
    flight = fly_on_grid(dataclasses.replace(scenario, duration_s=FAULT_FLIGHT_S), 0.2)
    samples = run_detector(calibration, flight.detector_flight, P_FA)
    combined = np.array([s.time_s for s in samples if s.combined_alarm])
    first = {name: next((s.time_s - ONSET_S for s in samples if s.time_s >= ONSET_S
                         and raised(s)), None)
             for name, raised in (("roll", lambda s: s.alarm[0]),
                                  ("parameters", lambda s: s.parameter_alarm),
                                  ("combined", lambda s: s.combined_alarm))}
    print(f"first alarms after the onset [s]: {first}; combined alarms before it: "
          f"{int((combined < ONSET_S).sum())}")
    assert combined.size and not (combined < ONSET_S).any()
    assert first["combined"] <= 10.0


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_the_propulsion_channel_sees_a_thrust_loss_in_the_throttle_it_needs():
    """The shipped propulsion_loss scenario (20 % of the thrust from 100 s), the propulsion
    channel calibrated on the flight's own first 95 s: its throttle bias c (the throttle
    needed in level, unbanked flight) rises, from 200 s on above every value it had before
    the loss (measured with seeds 7, 8, 9: 5.3-7.8 of its within-flight spread). Across
    flights its spread is wider (winds, turbulence): no combined alarm, docs/detector.md."""
    scenario = load_scenario(scenarios_dir() / "propulsion_loss.yaml")
    (fault,) = scenario.faults
    assert (fault.name, fault.start_s, fault.magnitude_pct) == ("propulsion_loss", 100.0, 20.0)
    flight = fly_on_grid(scenario, 0.2).detector_flight
    before_loss = flight.times_s < 95.0
    calibration = calibrate([DetectorFlight(*(column[before_loss] for column in flight[:4]))],
                            generators=("propulsion",))
    samples = run_detector(calibration, flight, P_FA)
    times_s = np.array([s.time_s for s in samples])
    bias = np.array([s.theta["propulsion"][2] for s in samples])
    settled, lost = bias[(times_s > 60.0) & (times_s < 100.0)], bias[times_s >= 200.0]
    print(f"throttle bias before the loss {settled.mean():.3f} +- {settled.std():.4f} "
          f"(largest {settled.max():.3f}), from 200 s on {lost.mean():.3f} "
          f"(smallest {lost.min():.3f})")
    assert lost.min() > settled.max()
    assert lost.mean() - settled.mean() > 4.0 * settled.std()
