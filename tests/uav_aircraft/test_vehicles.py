"""Aircraft folders: every shipped vehicle loads, trims and flies its own scenario; a folder
that cannot be flown is one line; ALFA's actuator failures pin the outputs they name, on
every vehicle."""

from __future__ import annotations

import dataclasses
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from helpers.repo import REPO_ROOT
from uav_aircraft import paths, vehicles
from uav_aircraft.fdm import M_PER_FT, create_fdm
from uav_aircraft.paths import aircraft_dir
from uav_aircraft.propeller import Propeller
from uav_aircraft.trim import trim_level_flight
from uav_aircraft.vehicles import VehicleError, load_vehicle, vehicle_names
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_sim.scenario import ScenarioError, SeededFault, load_scenario, vehicle_scenario_path
from uav_sim.simulation import Simulation

ALFA_CRUISE_THROTTLE = 0.31  # median of vfr_hud's throttle, ALFA's 2018-07-18 no-failure flight
ELEVATOR, AILERON, THROTTLE = (CONTROL_CHANNELS.index(name)
                               for name in ("elevator", "aileron", "throttle"))
ENGINE_SPEED = STATE_CHANNELS.index("engine_speed")


@pytest.mark.timeout(30)
def test_the_shipped_vehicles_are_the_aerosonde_and_the_carbon_z():
    assert vehicle_names() == ("aerosonde", "carbon_z")
    carbon_z = load_vehicle("carbon_z")
    assert carbon_z.surface_limit_rad == pytest.approx(math.radians(25.0), abs=1e-4)
    assert carbon_z.propeller_file.name == "carbon_z_propeller.xml"
    assert load_scenario(vehicle_scenario_path(carbon_z.name, "default")).vehicle == "carbon_z"
    assert load_scenario(vehicle_scenario_path(carbon_z.name, "fault_free")).faults == ()


@pytest.mark.timeout(30)
@pytest.mark.parametrize("name", ["aerosonde", "carbon_z"])
def test_each_vehicle_trims_at_its_scenarios_airspeed(name):
    vehicle = load_vehicle(name)
    initial = load_scenario(vehicle_scenario_path(vehicle.name, "default")).initial
    fdm = create_fdm(vehicle)
    fdm["ic/h-sl-ft"] = initial.altitude_m / M_PER_FT
    fdm["fcs/mixture-cmd-norm"] = 1.0
    trim = trim_level_flight(fdm, initial.airspeed_mps, vehicle, Propeller.from_vehicle(vehicle))
    print(f"{name}: {trim}")
    assert np.all(np.abs(trim.residual_accelerations) < 1e-4)
    assert 0.0 < trim.alpha_rad < 0.1 and abs(trim.elevator_rad) < vehicle.surface_limit_rad / 2
    if name == "carbon_z":  # its motor's map was chosen so (carbon_z_motor.xml)
        assert trim.throttle == pytest.approx(ALFA_CRUISE_THROTTLE, abs=0.03)


@pytest.mark.timeout(60)
def test_the_carbon_z_flies_its_mission_within_its_envelope():
    scenario = load_scenario(vehicle_scenario_path("carbon_z", "fault_free"))
    simulation = Simulation(dataclasses.replace(scenario, duration_s=120.0))
    samples = [simulation.step() for _ in range(round(120.0 / simulation.period_s))]
    altitude_m = np.array([s.true_state[2] for s in samples])
    airspeed_mps = np.array([s.true_air_data[0] for s in samples])
    north_east_m = np.array([s.position_ne_m for s in samples])
    print(f"altitude {altitude_m.min():.1f}..{altitude_m.max():.1f} m, airspeed "
          f"{airspeed_mps.min():.2f}..{airspeed_mps.max():.2f} m/s")
    assert np.all(np.abs(altitude_m - scenario.initial.altitude_m) < 10.0)
    assert np.all(np.abs(airspeed_mps - scenario.initial.airspeed_mps) < 2.0)
    assert north_east_m[:, 0].max() > 400.0 and north_east_m[:, 1].max() > 300.0  # legs flown


@pytest.fixture
def copied_aircraft(tmp_path, monkeypatch):
    """The aircraft folders copied where a test may break them, load_vehicle reading there."""
    copy = tmp_path / "aircraft"
    shutil.copytree(aircraft_dir(), copy)
    monkeypatch.setattr(vehicles, "aircraft_dir", lambda: copy)
    load_vehicle.cache_clear()
    yield copy
    load_vehicle.cache_clear()


@pytest.mark.timeout(30)
@pytest.mark.parametrize(("change", "words"), [
    (("autopilot:\n", "autopilot:\n  yaw_p: 1.0\n"), "unknown key 'autopilot.yaw_p'"),
    (("vehicle: carbon_z", "vehicle: aerosonde"), "'vehicle' is 'aerosonde', but the folder is"),
    (("airspeed_mps: [10.5, 35.0]", "airspeed_mps: [35.0, 10.5]"),
     "'air_data_range.airspeed_mps' must be [low, high] with low < high"),
])
def test_a_vehicle_folder_that_cannot_be_flown_is_one_line(copied_aircraft, change, words):
    path = copied_aircraft / "carbon_z" / "vehicle.yaml"
    path.write_text(path.read_text().replace(*change))
    with pytest.raises(VehicleError) as refused:
        load_vehicle("carbon_z")
    assert str(refused.value).startswith(f"vehicle file {path}: ") and words in str(refused.value)
    assert "\n" not in str(refused.value)


@pytest.mark.timeout(10)
def test_a_vehicle_scenario_not_shipped_is_one_line(copied_aircraft):
    path = copied_aircraft / "carbon_z" / "vehicle.yaml"
    path.write_text(path.read_text().replace("carbon_z_fault_free.yaml", "nowhere.yaml"))
    assert load_vehicle("carbon_z").fault_free_scenario_file == "nowhere.yaml"
    with pytest.raises(ScenarioError) as refused:
        vehicle_scenario_path("carbon_z", "fault_free")
    assert str(refused.value).startswith(f"vehicle file {path}: its fault_free scenario "
                                         "nowhere.yaml is not in ")
    assert "\n" not in str(refused.value)


@pytest.mark.timeout(10)
def test_an_unknown_vehicle_names_the_known_ones():
    with pytest.raises(VehicleError, match=r"^unknown vehicle 'cessna' \(known: aerosonde, "
                                           r"carbon_z\)$"):
        load_vehicle("cessna")


def flown_with(vehicle: str, fault: SeededFault, duration_s: float = 16.0) -> list:
    """The vehicle's fault-free scenario flown for duration_s with one fault seeded."""
    scenario = load_scenario(vehicle_scenario_path(vehicle, "fault_free"))
    simulation = Simulation(dataclasses.replace(scenario, duration_s=duration_s,
                                                sensors=dataclasses.replace(scenario.sensors,
                                                                            noise=False),
                                                faults=(fault,)))
    return [simulation.step() for _ in range(round(duration_s / simulation.period_s))]


@pytest.mark.timeout(60)
@pytest.mark.parametrize("vehicle", ["aerosonde", "carbon_z"])
def test_alfas_failures_pin_the_output_they_name(vehicle):
    limit = load_vehicle(vehicle).surface_limit_rad
    start_s = 8.0
    stuck = flown_with(vehicle, SeededFault("elevator_stuck", start_s, 0.0, 100.0, 0.1))
    after = [s for s in stuck if s.time_s >= start_s + 0.1]
    before = [s for s in stuck if s.time_s < start_s]
    assert all(s.controls[ELEVATOR] == pytest.approx(0.1 * limit, rel=1e-9) for s in after)
    assert len({round(s.controls[ELEVATOR], 6) for s in before}) > 10  # it moved before
    assert all(s.seeded_faults_pct[-3] == (100.0 if s.time_s >= start_s else 0.0)
               for s in stuck)  # elevator_stuck's column of the seeded vector
    # one aileron at 0: the pair deflects half of what the autopilot commands
    one = flown_with(vehicle, SeededFault("left_aileron_stuck", start_s, 0.0, 100.0))
    both = flown_with(vehicle, SeededFault("aileron_stuck", start_s, 0.0, 100.0))
    assert all(s.controls[AILERON] == 0.0 for s in both if s.time_s >= start_s + 0.1)
    assert max(abs(s.controls[AILERON]) for s in one if s.time_s >= start_s + 0.1) > 1e-4
    cut = flown_with(vehicle, SeededFault("engine_cut", start_s, 0.0, 100.0))
    assert all(s.controls[THROTTLE] == 0.0 for s in cut if s.time_s >= start_s + 0.1)
    rpm = [s.state[ENGINE_SPEED] for s in cut]
    print(f"{vehicle}: engine speed {rpm[0]:.0f} rpm before the cut, {rpm[-1]:.0f} rpm 8 s on")
    assert rpm[-1] < 0.7 * rpm[0]  # windmilling, no longer driven


@pytest.mark.timeout(30)
def test_calibration_commands_write_into_the_source_trees_vehicle_folder():
    """Whether the code runs from the install space (as here) or the source tree, a
    calibration command's default output is the vehicle's folder in ros_ws/src."""
    assert Path(paths.__file__).resolve().is_relative_to(REPO_ROOT / "ros_ws" / "install")
    assert paths.calibration_output_path("carbon_z", vehicles.FAILURE_SIGNATURES_FILE) == (
        REPO_ROOT / "ros_ws/src/uav_aircraft/aircraft/carbon_z/failure_signatures.yaml")
