"""The random aircraft study's draws and its judge of the default targets (the flights
themselves are the study's: docs/results.md)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from uav_aircraft.flown_aircraft import NOMINAL, coefficient_names
from uav_aircraft.vehicles import load_vehicle
from uav_sim.scenario import load_scenario

from studies.model_error import CALIBRATION_FLIGHTS
from studies.random_aircraft import (
    DRAW,
    MEASUREMENT_ERROR,
    calibration_scenarios,
    drawn_aircraft,
    measured_mass_properties,
    missed_targets,
)


@pytest.mark.timeout(30)
def test_each_aircraft_is_drawn_within_its_ranges_and_again_the_same():
    aircraft = [drawn_aircraft(1, k) for k in range(1, 21)]
    assert drawn_aircraft(1, 3) == aircraft[2] and drawn_aircraft(2, 3) != aircraft[2]
    for one in aircraft:
        assert abs(one.mass_scale - 1.0) <= DRAW["mass_scale"]
        assert all(abs(v - 1.0) <= DRAW["inertia_scale"] for v in one.inertia_scale)
        assert all(abs(v) <= DRAW["cg_offset_m"] for v in one.cg_offset_m)
        assert abs(one.thrust_scale - 1.0) <= DRAW["thrust_scale"]
        assert [name for name, _ in one.coefficients] == list(coefficient_names(load_vehicle()))
        assert all(abs(v - 1.0) <= DRAW["coefficient"] for _, v in one.coefficients)
        assert abs(one.sensor_bias.airspeed_scale - 1.0) <= DRAW["airspeed_scale"]
        assert abs(one.sensor_bias.angle_of_attack_deg) <= DRAW["vane_bias_deg"]
    spread = max(a.mass_scale for a in aircraft) - min(a.mass_scale for a in aircraft)
    assert spread > DRAW["mass_scale"]  # the draws use the range, not one corner of it


def fault(seeded_final: float, final: float, rmse: float, delay: float | None,
          largest: float = 0.5) -> dict:
    return {"seeded": seeded_final > 0, "seeded_final_pct": seeded_final,
            "estimate_final_pct": final, "rmse_pct": rmse, "max_abs_error_pct": largest,
            "detection_delay_s": delay}


@pytest.mark.timeout(30)
def test_the_targets_are_judged_as_stated():
    fault_free = ({"a": fault(0.0, 0.3, 0.2, None), "b": fault(0.0, 0.3, 0.2, None)}, [])
    good = {"a": fault(20.0, 21.9, 2.9, 9.5), "b": fault(10.0, 9.1, 1.4, 3.0)}
    assert missed_targets({"fault_free": fault_free, "default": (good, [])}) == []
    bad = {"a": fault(20.0, 22.1, 3.1, 10.5), "b": fault(10.0, 10.0, 1.0, None)}
    missed = missed_targets({"fault_free": ({"a": fault(0.0, 1.0, 0.5, None, largest=2.0),
                                             "b": fault(0.0, 0.3, 0.2, None)}, ["a"]),
                             "default": (bad, ["b"])})
    assert missed == ["fault-free a 2.00 %", "false alarm a", "false alarm b",
                      "a RMS 3.10 % of 20", "a found 10.5 s", "a final 22.10 % for 20",
                      "b found never"]


@pytest.mark.timeout(30)
def test_no_two_aircraft_share_their_calibration_flights_noise():
    seeds = {index: [s.seed for s in calibration_scenarios(NOMINAL, index)]
             for index in range(4)}
    assert seeds[0] == [seed for _, seed, _, _ in CALIBRATION_FLIGHTS]  # model_error's
    flat = [seed for flights in seeds.values() for seed in flights]
    assert len(set(flat)) == len(flat)


@pytest.mark.timeout(30)
def test_mass_properties_are_measured_within_the_stated_error():
    for k in range(1, 11):
        flown = drawn_aircraft(1, k)
        measured = measured_mass_properties(flown, 1, k)
        assert np.abs(np.subtract(measured.cg_offset_m, flown.cg_offset_m)).max() <= \
            MEASUREMENT_ERROR["cg_offset_m"]
        assert np.abs(np.divide(measured.inertia_scale, flown.inertia_scale) - 1.0).max() <= \
            MEASUREMENT_ERROR["inertia_scale"]
        assert measured.inertia_scale != flown.inertia_scale  # measured, not copied
        assert dataclasses.replace(measured, cg_offset_m=NOMINAL.cg_offset_m,
                                   inertia_scale=NOMINAL.inertia_scale) == NOMINAL


@pytest.mark.timeout(30)
@pytest.mark.parametrize("vehicle", ["aerosonde", "carbon_z"])
def test_a_plan_flies_each_aircraft_in_its_own_noise_and_the_vehicle_is_its_own(vehicle):
    plan = tuple(load_vehicle(vehicle).calibration_plan_files)
    flown = drawn_aircraft(2, 1, vehicle)
    assert [name for name, _ in flown.coefficients] == list(
        coefficient_names(load_vehicle(vehicle)))
    flights = {index: calibration_scenarios(flown, index, plan=plan) for index in range(3)}
    assert all(f.vehicle == vehicle and f.aircraft == flown and f.manoeuvres
               for f in flights[1])
    seeds = [f.seed for index in flights for f in flights[index]]
    assert len(set(seeds)) == len(seeds)
    assert [f.seed for f in flights[0]] == [load_scenario(path).seed for path in plan]
