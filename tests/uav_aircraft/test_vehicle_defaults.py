"""What the vehicle's folder gives where a log or link does not say it (the fuel on board),
and which vehicle a command's recordings or logs say flew, a disagreeing --vehicle refused
in one line."""

from __future__ import annotations

import pytest
from uav_aircraft.fdm import KG_PER_LB, fuel_on_board_kg
from uav_aircraft.vehicle_parameter import FUEL_MASS_PARAMETER, VEHICLE_FUEL_KG
from uav_aircraft.vehicles import VehicleError, load_vehicle, vehicle_of_sources

AEROSONDE_FUEL_LBS = 11.0231  # aerosonde.xml's propulsion/fuel-loaded-lbs (5 kg)


@pytest.mark.timeout(30)
def test_the_fuel_on_board_is_the_vehicle_models_unless_given():
    assert FUEL_MASS_PARAMETER.default == VEHICLE_FUEL_KG < 0.0
    assert fuel_on_board_kg(VEHICLE_FUEL_KG, load_vehicle("aerosonde")) == pytest.approx(
        AEROSONDE_FUEL_LBS * KG_PER_LB, rel=1e-6)
    assert fuel_on_board_kg(VEHICLE_FUEL_KG, load_vehicle("carbon_z")) == 0.0  # electric
    assert fuel_on_board_kg(2.5, load_vehicle("aerosonde")) == 2.5
    assert fuel_on_board_kg(0.0, load_vehicle("aerosonde")) == 0.0  # given: an empty tank


@pytest.mark.timeout(10)
def test_the_vehicle_the_sources_say_is_taken_and_a_given_one_must_agree():
    said = {"bag1": "carbon_z", "bag2": "carbon_z", "flight.bin": None}
    assert vehicle_of_sources(said, None) == "carbon_z"
    assert vehicle_of_sources(said, "carbon_z") == "carbon_z"
    with pytest.raises(VehicleError) as refused:
        vehicle_of_sources(said, "aerosonde")
    assert str(refused.value) == ("--vehicle aerosonde, but carbon_z flew bag1, bag2: leave "
                                  "out --vehicle or give carbon_z")


@pytest.mark.timeout(10)
def test_sources_of_two_vehicles_are_refused_in_one_line():
    with pytest.raises(VehicleError) as refused:
        vehicle_of_sources({"a": "aerosonde", "b": "carbon_z", "c": "aerosonde"}, None)
    assert str(refused.value) == ("different vehicles flew these: aerosonde a, c; carbon_z b: "
                                  "give one vehicle's at a time")


@pytest.mark.timeout(10)
def test_sources_that_say_no_vehicle_take_the_given_one_or_the_default_and_say_so():
    lines: list[str] = []
    assert vehicle_of_sources({"flight.bin": None}, None, say=lines.append) == "aerosonde"
    assert vehicle_of_sources({"flight.bin": None}, "carbon_z", say=lines.append) == "carbon_z"
    assert lines == ["flight.bin: no vehicle said; taken as aerosonde (the default; "
                     "--vehicle NAME if another flew)",
                     "flight.bin: no vehicle said; taken as carbon_z"]
    with pytest.raises(VehicleError, match="unknown vehicle 'glider'"):
        vehicle_of_sources({"a": "glider"}, None)
