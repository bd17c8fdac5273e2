"""The calibration bias study's conditions and its summary (the calibrations themselves are
the study's: docs/results.md)."""

from __future__ import annotations

import pytest
from uav_aircraft.flown_aircraft import NOMINAL

from studies.calibration_bias import CONDITIONS, flights_in, summary
from studies.random_aircraft import calibration_scenarios


@pytest.mark.timeout(30)
def test_each_condition_changes_only_the_turbulence_and_the_sensor_noise():
    flown = calibration_scenarios(NOMINAL, 1)
    for condition, (turbulence, noise) in CONDITIONS.items():
        flights = flights_in(condition, 1)
        assert [f.seed for f in flights] == [f.seed for f in flown]
        for flight, original in zip(flights, flown, strict=True):
            assert flight.wind.turbulence == turbulence and flight.sensors.noise == noise
            assert flight.sensors.air_data
            assert (flight.wind.north_mps, flight.initial, flight.aircraft) == (
                original.wind.north_mps, original.initial, NOMINAL)
    assert flights_in("turbulence, sensor noise", 1) == flown  # the study's own flights


@pytest.mark.timeout(30)
def test_the_summary_is_over_the_seed_sets_of_each_condition():
    rows = [{"condition": condition, "values": {"CDmin": [value, 2.0 * value]}}
            for condition in CONDITIONS for value in (1.0, 2.0, 6.0)]
    table = summary(rows, ("CDmin",))
    for condition in CONDITIONS:
        assert table[condition]["CDmin"] == {"mean": 3.0, "min": 1.0, "max": 6.0,
                                             "posterior_std": 6.0}
