"""Residuals and sensitivities of the JSBSim prediction model on simulated flights.

The simulator and the prediction model share the aircraft definition, so in calm air and
without faults the residual is what the model cannot see between 20 Hz samples; under
constant faults it is S f (embedded-estimation paper, eq. 2-8).
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers.flights import column
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import PAPER_FAULT_NAMES
from uav_fault_estimator.estimation.prediction import aircraft_predictor_factory
from uav_fault_estimator.estimation.residuals import RESIDUAL_CHANNELS

LINEAR_X, LINEAR_Z, ANGULAR_X, ANGULAR_Z = 0, 2, 3, 5


def rms(values: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(values**2, axis=0))


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_fault_free_residuals_are_below_5_percent_of_any_10_percent_fault(residual_flight):
    fault_free_rms = rms(column(residual_flight({}), "residual"))
    faulty_rms = np.array([
        rms(column(residual_flight({name: 10.0}), "residual")) for name in PAPER_FAULT_NAMES
    ])
    largest_rms = faulty_rms.max(axis=0)
    for channel, free, faults in zip(RESIDUAL_CHANNELS, fault_free_rms, faulty_rms.T,
                                     strict=True):
        print(f"{channel:>9}: fault-free RMS {free:.2e}, under 10 % faults "
              + ", ".join(f"{value:.2e}" for value in faults)
              + f"  ratio {free / faults.max():.2%}")
    assert np.all(fault_free_rms < 0.05 * largest_rms)


LINEARITY_CASES = [
    *({name: value} for name in PAPER_FAULT_NAMES for value in (5.0, 15.0)),
    dict.fromkeys(PAPER_FAULT_NAMES, 10.0),
]


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_without_engine_speed_the_steady_propeller_keeps_faults_apart(residual_flight):
    """An autopilot that streams no engine speed (PX4): the models turn the propeller at
    its steady speed for the throttle. Every row is formed and the fault-free residuals stay
    below 5 % of a 10 % fault's, as with the measured speed (the engine's lag, left out,
    is the largest part: 3.8 % in linear_x, against 0.5 % measured)."""
    fault_free = column(residual_flight({}, engine_speed_measured=False), "residual")
    faulty_rms = np.array([
        rms(column(residual_flight({name: 10.0}, engine_speed_measured=False), "residual"))
        for name in PAPER_FAULT_NAMES
    ])
    assert np.all(np.isfinite(fault_free))
    print("fault-free RMS over the largest 10 % fault's:",
          np.round(rms(fault_free) / faulty_rms.max(axis=0), 4))
    assert np.all(rms(fault_free) < 0.05 * faulty_rms.max(axis=0))


@pytest.mark.timeout(300)
@pytest.mark.slow
@pytest.mark.parametrize(
    "faults_pct", LINEARITY_CASES,
    ids=["+".join(f"{name}={value:g}" for name, value in case.items())
         for case in LINEARITY_CASES],
)
def test_residual_is_s_times_f_under_constant_faults(residual_flight, faults_pct):
    samples = residual_flight(faults_pct)
    fault_vector = np.array([faults_pct.get(name, 0.0) for name in PAPER_FAULT_NAMES])
    residual = column(samples, "residual")
    explained = column(samples, "sensitivity") @ fault_vector
    relative_error = np.linalg.norm(residual - explained) / np.linalg.norm(residual)
    print(f"{faults_pct}: |y - S f| / |y| = {relative_error:.4f}")
    assert relative_error <= 0.1


@pytest.mark.timeout(300)
def test_sensitivity_columns_have_the_signs_of_the_physics(residual_flight):
    """Body axes, z down. Lift loss: less upward force (+z), the damaged wing drops (roll
    towards it: + for the right wing); drag increase: deceleration (-x), the nose yaws
    towards the damaged wing (+ for the right wing). Every sample, straight and turning."""
    sensitivity = column(residual_flight({}), "sensitivity")  # (samples, 6, p)
    by_fault = {name: sensitivity[:, :, j] for j, name in enumerate(PAPER_FAULT_NAMES)}
    for name, values in by_fault.items():
        print(f"{name:>25}: S mean " + " ".join(f"{v:+.2e}" for v in values.mean(axis=0)))
    for side, sign in (("right", 1.0), ("left", -1.0)):
        lift, drag = by_fault[f"{side}_wing_lift_loss"], by_fault[f"{side}_wing_drag_increase"]
        assert np.all(lift[:, LINEAR_Z] > 0) and np.all(sign * lift[:, ANGULAR_X] > 0)
        assert np.all(drag[:, LINEAR_X] < 0) and np.all(sign * drag[:, ANGULAR_Z] > 0)
    # the wings mirror each other: same force, opposite moments
    right, left = by_fault["right_wing_lift_loss"], by_fault["left_wing_lift_loss"]
    assert right[:, ANGULAR_X].mean() == pytest.approx(-left[:, ANGULAR_X].mean(), rel=0.05)


@pytest.mark.timeout(300)
def test_wind_error_columns_have_the_signs_of_the_physics(residual_flight):
    """On the northbound first leg: more tail wind than estimated (north error) means less
    airspeed, so less drag and more propeller thrust (+x); more downdraft than estimated
    (down error) means a smaller angle of attack, so less lift (+z)."""
    samples = residual_flight({}, wind_error_step_mps=1.0)
    northbound = column(samples, "time_s") < 60.0
    sensitivity = column(samples, "sensitivity")[northbound]  # (samples, 6, 4 + 3)
    north, down = (sensitivity[:, :, len(PAPER_FAULT_NAMES) + axis] for axis in (0, 2))
    print("S of the north error, mean: " + " ".join(f"{v:+.3f}" for v in north.mean(axis=0)))
    print("S of the down error, mean:  " + " ".join(f"{v:+.3f}" for v in down.mean(axis=0)))
    assert np.all(north[:, LINEAR_X] > 0) and np.all(down[:, LINEAR_Z] > 0)


@pytest.mark.timeout(60)
def test_an_unknown_fault_name_is_refused_by_name():
    with pytest.raises(ValueError, match="wing_fell_off"):
        aircraft_predictor_factory(load_vehicle())({"wing_fell_off": 5.0})
