"""The output-error fit: the model flown open-loop from the logged inputs follows its own
aircraft's flight, and the fit finds an aircraft's pitch derivatives from one pitch
doublet of the calibration plan, without vanes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from helpers.flights import calm
from uav_aircraft.flown_aircraft import NOMINAL
from uav_aircraft.vehicles import load_vehicle
from uav_fault_estimator.chain.offline import sensor_flight
from uav_fault_estimator.estimation.model_calibration import SensorFlight
from uav_fault_estimator.estimation.model_parameters import changed, model_parameter
from uav_fault_estimator.estimation.output_error import (
    OUTPUT_NAMES,
    Manoeuvre,
    ManoeuvreFlyer,
    fit_output_error,
    output_errors,
)
from uav_sim.scenario import load_scenario

# The aircraft flown: its pitch differs from the model's by a few percent each [%].
TRUTH = {"CLalpha": 5.0, "Cmalpha": 8.0, "Cmq": -10.0, "Cmde": 4.0}
LOG_RATE_HZ = 120.0  # the inputs' steps resolved (20 Hz smears them by up to 50 ms)
DOUBLET_S = (89.0, 103.0)  # plan_25's pitch doublet: 90 s, steps of 6 s
PITCH = [OUTPUT_NAMES.index(name) for name in ("pitch", "pitch_rate", "angle_of_attack")]


@pytest.fixture(scope="module")
def doublet() -> Manoeuvre:
    vehicle = load_vehicle("aerosonde")
    plan = load_scenario(vehicle.folder / "calibration_plan" / "plan_25.yaml")
    scenario = dataclasses.replace(calm(plan, DOUBLET_S[1] + 1.0),
                                   aircraft=changed(NOMINAL, TRUTH))
    flight = sensor_flight(scenario, LOG_RATE_HZ)
    first, last = np.searchsorted(flight.times_s, DOUBLET_S)
    return Manoeuvre(flight, int(first), int(last))


def without_vanes(manoeuvre: Manoeuvre) -> Manoeuvre:
    """The manoeuvre as a log without flow-angle vanes holds it."""
    air_data = manoeuvre.flight.air_data.copy()
    air_data[:, 1:] = math.nan
    flight = SensorFlight(manoeuvre.flight.name, manoeuvre.flight.times_s,
                          manoeuvre.flight.states, manoeuvre.flight.controls,
                          manoeuvre.flight.winds_ned_mps, air_data)
    return Manoeuvre(flight, manoeuvre.start, manoeuvre.stop)


@pytest.mark.timeout(120)
def test_the_aircraft_flown_open_loop_follows_its_flight(doublet):
    """From the measured first sample, the inputs as logged: with the flown aircraft's
    parameters the pitch, pitch rate and angle of attack stay on the flight's (RMS errors
    100 times below the doublet's swing; measured 0.17 and 0.11 mrad, 1.6 mrad/s), with the
    model's the pitch and angle of attack are 20 times further off."""
    vehicle = load_vehicle("aerosonde")
    measured = doublet.measured()
    swing = np.ptp(measured[:, PITCH], axis=0)

    def rms_errors(base) -> np.ndarray:
        flown = ManoeuvreFlyer(vehicle, base).fly([], np.zeros(0), doublet,
                                                  doublet.first_guess())
        return np.sqrt(np.mean(output_errors(measured, flown)[:, PITCH] ** 2, axis=0))

    own = rms_errors(changed(NOMINAL, TRUTH))
    model = rms_errors(NOMINAL)
    print("swing", swing, "own aircraft", own, "model", model)
    assert np.all(own < 0.01 * swing)
    assert model[0] > 10.0 * own[0] and model[2] > 10.0 * own[2]


@pytest.mark.timeout(300)
def test_the_fit_finds_the_pitch_derivatives_without_vanes(doublet):
    """Calm air, noise-free sensors, one doublet, no vanes: each derivative within 0.5 % of
    the flown one, within its bounds, with a finite Cramer-Rao deviation."""
    vehicle = load_vehicle("aerosonde")
    parameters = [model_parameter(name, vehicle) for name in TRUTH]
    fit = fit_output_error(ManoeuvreFlyer(vehicle), [without_vanes(doublet)],
                           parameters, relaxations=1)
    print({name: (round(fit.values[name], 3), round(fit.deviations[name], 4)) for name in TRUTH},
          "integrations", fit.integrations)
    for name, true_pct in TRUTH.items():
        # the coefficient is the file's times (1 + value / 100)
        assert abs(fit.values[name] - true_pct) < 0.5 * (1.0 + true_pct / 100.0), name
        assert 0.0 < fit.deviations[name] < 1.0, name
