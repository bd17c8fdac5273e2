#!/usr/bin/env python3
"""The model calibration on aircraft nobody chose: random airframes, calibrated and flown.

    python -m studies.random_aircraft [--vehicle aerosonde] [--count 40] [--seed 1]
        [--parameters A,B,...] [--plan [DIR]] [--json FILE] [--workers N]

Draws --count aircraft at random (numpy's generator seeded with --seed, one stream per
aircraft) about the vehicle's model from the scenario `aircraft:` block's parameters, each
uniform within DRAW: empty mass +-5 %, inertia about each axis +-10 %, CG +-2 cm per axis,
thrust +-5 %, every one of the XML's aerodynamic coefficients +-15 %, the pitot's scale
+-3 %, the vanes' biases +-0.6 deg; plus the model's own aircraft (`model`, every parameter
nominal). Each aircraft, through the offline chain (uav_fault_estimator.chain.offline), as
studies/model_error.py does it through the graph: its calibration flights, either three
ordinary fault-free ones (the Aerosonde's only: model_error.CALIBRATION_FLIGHTS, 22, 25 and
28 m/s, winds of 5-6 m/s from three directions) or with --plan the scenario files of a
calibration plan (without DIR the vehicle's calibration_plan/: manoeuvre flights), their
seeds those of the files (501-503) for the model's own aircraft, plus SEED_STRIDE times its
number for a drawn one, so that no two aircraft share their turbulence and sensor noise;
the model calibration (estimation/model_calibration.py, --parameters or the default set)
and its check (estimation/calibration_check.py), then two test flights of the calibrated
model, the vehicle's shipped fault_free and default scenarios (seed 7), judged against the
default targets (uav_fault_estimator/reporting/targets.py). Prints a line per aircraft and
the totals: how many meet the targets, and whether each that does not was flagged by the
check. Aircraft run one per worker (the campaign layer); about 1.5 minutes each on one core.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np
from uav_aircraft.flown_aircraft import NOMINAL, FlownAircraft, SensorBias, coefficient_names
from uav_aircraft.vehicles import DEFAULT_VEHICLE, load_vehicle, vehicle_names
from uav_common.channels import DETECTION_THRESHOLD_PCT as THRESHOLD_PCT
from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.chain.offline import fly_and_estimate, sensor_flight, wind_variant
from uav_fault_estimator.estimation.calibration_check import check_calibration
from uav_fault_estimator.estimation.estimator_step import SETTLE_S
from uav_fault_estimator.estimation.model_calibration import (
    ModelCalibration,
    SensorFlight,
    calibrate,
)
from uav_fault_estimator.estimation.model_parameters import DEFAULT_PARAMETERS, parameter_list
from uav_fault_estimator.estimation.noise_model import NoiseCalibration, load_noise_calibration
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.reporting import targets
from uav_fault_estimator.reporting.metrics import fault_metrics
from uav_sim.scenario import Scenario, SetpointChange, load_scenario, vehicle_scenario_path

from studies.model_error import CALIBRATION_FLIGHTS

# Half-widths of the uniform draws, about the model's values
DRAW = {"mass_scale": 0.05, "inertia_scale": 0.10, "cg_offset_m": 0.02, "thrust_scale": 0.05,
        "coefficient": 0.15, "airspeed_scale": 0.03, "vane_bias_deg": 0.6}
MODEL = "model"
SEED_STRIDE = 1000  # calibration flight seeds of aircraft k: the model's plus k times this
# With --excite: each calibration flight's setpoint changes (start [s], airspeed change
# [m/s], altitude change [m] from the flight's own): a speed step and back, a climb and back,
# a faster descent and back; throttle swings from near idle to near full (thrust against
# drag and mass, which level flight at one speed ties together).
EXCITATION = ((60.0, 4.0, 0.0), (100.0, 0.0, 0.0), (140.0, 0.0, 30.0), (180.0, 0.0, 0.0),
              (220.0, 4.0, -30.0), (260.0, 0.0, 0.0))
# What the calibration flights are flown in: name -> (turbulence level, sensor noise); the
# last is the flights' own, the default. --calibration-condition takes the others, to tell
# what the flights' turbulence and noise cost from what no fault-free flight of this kind
# shows (the calm, ideal one).
CONDITIONS = {"calm air, ideal sensors": ("none", False),
              "calm air, sensor noise": ("none", True),
              "turbulence, ideal sensors": ("from_wind", False),
              "turbulence, sensor noise": ("from_wind", True)}
OWN_CONDITION = "turbulence, sensor noise"
# With --measured-mass-properties: half-widths of the ground measurement's error, uniform
# (a CG on a balance within a few millimetres, an inertia from a pendulum within a few %)
MEASUREMENT_ERROR = {"cg_offset_m": 0.003, "inertia_scale": 0.03}


def drawn_aircraft(seed: int, index: int, vehicle: str = DEFAULT_VEHICLE) -> FlownAircraft:
    """Aircraft number index of the study seeded with seed (its own random stream), about
    the vehicle's model."""
    rng = np.random.default_rng([seed, index])

    def around(value: float, half_width: float, size: int | None = None):
        return value + rng.uniform(-half_width, half_width, size)

    return FlownAircraft(
        mass_scale=float(around(1.0, DRAW["mass_scale"])),
        inertia_scale=tuple(float(v) for v in around(1.0, DRAW["inertia_scale"], 3)),
        cg_offset_m=tuple(float(v) for v in around(0.0, DRAW["cg_offset_m"], 3)),
        thrust_scale=float(around(1.0, DRAW["thrust_scale"])),
        coefficients=tuple((name, float(around(1.0, DRAW["coefficient"])))
                           for name in coefficient_names(load_vehicle(vehicle))),
        sensor_bias=SensorBias(float(around(1.0, DRAW["airspeed_scale"])),
                               float(around(0.0, DRAW["vane_bias_deg"])),
                               float(around(0.0, DRAW["vane_bias_deg"]))))


def measured_mass_properties(aircraft: FlownAircraft, seed: int, index: int) -> FlownAircraft:
    """The nominal model with the aircraft's CG and inertia as a ground measurement gives
    them: the flown values off by up to MEASUREMENT_ERROR (its own random stream)."""
    rng = np.random.default_rng([seed, index, 1])
    return dataclasses.replace(
        NOMINAL,
        cg_offset_m=tuple(float(v) for v in np.asarray(aircraft.cg_offset_m) + rng.uniform(
            -MEASUREMENT_ERROR["cg_offset_m"], MEASUREMENT_ERROR["cg_offset_m"], 3)),
        inertia_scale=tuple(float(v) for v in np.asarray(aircraft.inertia_scale) * (
            1.0 + rng.uniform(-MEASUREMENT_ERROR["inertia_scale"],
                              MEASUREMENT_ERROR["inertia_scale"], 3))))


def calibration_scenarios(aircraft: FlownAircraft, index: int, excite: bool = False,
                          condition: str = OWN_CONDITION,
                          plan: tuple[Path, ...] = ()) -> list[Scenario]:
    """The three calibration flights of aircraft number index (0: the model's own), with
    the EXCITATION setpoint changes when excite, flown in the condition (CONDITIONS); or
    the plan's scenario files (a calibration plan's manoeuvre flights), each seed moved as
    the three's."""
    turbulence, noise = CONDITIONS[condition]
    if plan:
        return [dataclasses.replace(
            flight, aircraft=aircraft, seed=flight.seed + SEED_STRIDE * index,
            wind=dataclasses.replace(flight.wind, turbulence=turbulence),
            sensors=dataclasses.replace(flight.sensors, noise=noise))
            for flight in map(load_scenario, plan)]
    base = load_scenario(vehicle_scenario_path(DEFAULT_VEHICLE, "fault_free"))
    base = dataclasses.replace(base, wind=dataclasses.replace(base.wind, turbulence=turbulence),
                               sensors=dataclasses.replace(base.sensors, noise=noise))
    flights = []
    for airspeed_mps, seed, towards_deg, wind_mps in CALIBRATION_FLIGHTS:
        flight = wind_variant(base, seed + SEED_STRIDE * index, towards_deg, wind_mps)
        altitude_m = flight.initial.altitude_m
        setpoints = tuple(SetpointChange(start_s, airspeed_mps + speed_mps,
                                         altitude_m + climb_m)
                          for start_s, speed_mps, climb_m in EXCITATION) if excite else ()
        flights.append(dataclasses.replace(
            flight, aircraft=aircraft, setpoints=setpoints,
            initial=dataclasses.replace(flight.initial, airspeed_mps=airspeed_mps)))
    return flights


def test_metrics(aircraft: FlownAircraft, model: FlownAircraft,
                 vehicle: str = DEFAULT_VEHICLE) -> dict[str, tuple]:
    """(faults, false alarms) of the vehicle's fault_free and default test flights of the
    aircraft, the models being `model`."""
    return {base: fault_metrics(*fly_and_estimate(dataclasses.replace(
        load_scenario(vehicle_scenario_path(vehicle, base)), aircraft=aircraft),
        model=model), SETTLE_S, THRESHOLD_PCT) for base in ("fault_free", "default")}


def missed_targets(tests: dict[str, tuple]) -> list[str]:
    """Each default target (reporting/targets.py) the fault-free and default test flights
    miss, one phrase each (empty: all met)."""
    return [phrase for base in ("fault_free", "default") for phrase in
            targets.judge(*tests[base]).missed]


@dataclasses.dataclass(frozen=True)
class AircraftTask:
    """One aircraft of the study: its name and number, what is flown, the parameters
    fitted, and what the model is given as measured on the ground."""

    name: str
    index: int
    aircraft: FlownAircraft
    parameters: tuple[str, ...]
    measured: FlownAircraft = NOMINAL
    excite: bool = False
    condition: str = OWN_CONDITION
    plan: tuple[Path, ...] = ()
    vehicle: str = DEFAULT_VEHICLE


def calibrate_scenarios(scenarios: list[Scenario], parameters: tuple[str, ...],
                        measured: FlownAircraft = NOMINAL,
                        ) -> tuple[ModelCalibration, list[SensorFlight], NoiseCalibration]:
    """The scenarios (of one vehicle) flown offline and the named parameters calibrated
    from them, as calibrate_model.py does it; the calibration, the flights and the noise
    model used."""
    flights = [sensor_flight(scenario) for scenario in scenarios]
    vehicle = scenarios[0].vehicle
    noise = load_noise_calibration(vehicle=vehicle)
    calibration = calibrate(flights, parameters, ResidualSettings(vehicle=vehicle), noise,
                            log=lambda line: None, measured=measured)
    return calibration, flights, noise


def study_aircraft(task: AircraftTask) -> dict:
    """Calibrate, check, fly the test flights and judge them (the module docstring)."""
    started = time.monotonic()
    calibration, flights, noise = calibrate_scenarios(
        calibration_scenarios(task.aircraft, task.index, task.excite, task.condition,
                              task.plan),
        task.parameters,
        task.measured)
    warnings = check_calibration(calibration, flights, noise)
    tests = test_metrics(task.aircraft, calibration.aircraft, task.vehicle)
    missed = missed_targets(tests)
    fault_free, default = tests["fault_free"][0], tests["default"][0]
    return {
        "name": task.name, "flown": task.aircraft.to_dict(),
        "weighted_residual_per_row": round(calibration.reduced_chi_square, 3),
        "steps": calibration.steps,
        "calibrated": {name: [round(float(v), 3), round(float(s), 3)] for name, v, s in zip(
            calibration.names, calibration.values, calibration.posterior_std, strict=True)},
        "check": [warning.text for warning in warnings],
        "fault_free_largest_pct": {n: f["max_abs_error_pct"] for n, f in fault_free.items()},
        "default_final_pct": {n: f["estimate_final_pct"] for n, f in default.items()},
        "default_rmse_pct": {n: f["rmse_pct"] for n, f in default.items()},
        "default_delay_s": {n: f["detection_delay_s"] for n, f in default.items()},
        "false_alarms": tests["fault_free"][1] + tests["default"][1],
        "missed": missed, "meets_targets": not missed, "flagged": bool(warnings),
        "wall_s": round(time.monotonic() - started, 1)}


def summary(rows: list[dict]) -> dict:
    """The totals over the drawn aircraft (the model's own apart)."""
    drawn = [row for row in rows if row["name"] != MODEL]
    failing = [row for row in drawn if not row["meets_targets"]]
    return {"aircraft": len(drawn), "meet_targets": len(drawn) - len(failing),
            "failing_flagged": sum(row["flagged"] for row in failing),
            "failing_not_flagged": [row["name"] for row in failing if not row["flagged"]],
            "meeting_flagged": sum(row["flagged"] for row in drawn if row["meets_targets"])}


def print_row(row: dict) -> None:
    verdict = "meets" if row["meets_targets"] else "misses: " + "; ".join(row["missed"])
    flag = f"flagged ({len(row['check'])})" if row["flagged"] else "not flagged"
    print(f"{row['name']:<6} residual {row['weighted_residual_per_row']:.2f}/row, {flag}; "
          f"fault-free largest {max(row['fault_free_largest_pct'].values()):.2f} %; "
          f"{verdict}", flush=True)
    for text in row["check"]:
        print(f"         WARN {text}")


PLAN_OF_THE_VEHICLE = Path("calibration_plan")  # --plan without a folder


def plan_files(folder: Path | None, vehicle: str,
               parser: argparse.ArgumentParser) -> tuple[Path, ...]:
    """The scenario files of --plan's folder (the vehicle's own for PLAN_OF_THE_VEHICLE;
    none without --plan); a parser error for a folder without any, or for a vehicle other
    than the default without a plan (the three ordinary flights are the Aerosonde's)."""
    if folder is None:
        if vehicle != DEFAULT_VEHICLE:
            parser.error(f"--vehicle {vehicle} needs --plan: the three ordinary calibration "
                         f"flights are {DEFAULT_VEHICLE}'s")
        return ()
    files = (tuple(load_vehicle(vehicle).calibration_plan_files)
             if folder == PLAN_OF_THE_VEHICLE else tuple(sorted(folder.glob("*.yaml"))))
    if not files:
        parser.error(f"--plan: no scenario files (*.yaml) in {folder}")
    return files


def calibration_study_arguments(parser: argparse.ArgumentParser) -> argparse.Namespace:
    """A calibration study's command line, parsed: the parser's own arguments, then
    --vehicle, --parameters (checked, as a tuple), --excite, --plan (its files), --json FILE
    and the campaign's options."""
    parser.add_argument("--vehicle", choices=vehicle_names(), default=DEFAULT_VEHICLE)
    parser.add_argument("--parameters", default=",".join(DEFAULT_PARAMETERS))
    parser.add_argument("--excite", action="store_true",
                        help="fly EXCITATION's setpoint changes in the calibration flights")
    parser.add_argument("--plan", nargs="?", type=Path, const=PLAN_OF_THE_VEHICLE,
                        metavar="DIR", help="calibrate from a calibration plan's scenario "
                        "files (DIR; without: the vehicle's calibration_plan/) instead of the "
                        "three ordinary flights")
    parser.add_argument("--json", type=Path)
    add_campaign_arguments(parser)
    arguments = parser.parse_args()
    arguments.plan = plan_files(arguments.plan, arguments.vehicle, parser)
    try:
        arguments.parameters = parameter_list(arguments.parameters,
                                              load_vehicle(arguments.vehicle))
    except ValueError as error:
        parser.error(str(error))
    return arguments


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=40)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--measured-mass-properties", action="store_true",
                        help="give the model each aircraft's CG and inertia as measured on the "
                             "ground (within MEASUREMENT_ERROR)")
    parser.add_argument("--calibration-condition", choices=tuple(CONDITIONS),
                        default=OWN_CONDITION,
                        help="fly the calibration flights in this condition (default: their "
                             "own, %(default)s)")
    arguments = calibration_study_arguments(parser)
    parameters, excite = arguments.parameters, arguments.excite
    condition = arguments.calibration_condition
    plan, vehicle = arguments.plan, arguments.vehicle
    tasks = [AircraftTask(MODEL, 0, NOMINAL, parameters, excite=excite, condition=condition,
                          plan=plan, vehicle=vehicle)]
    for k in range(1, arguments.count + 1):
        aircraft = drawn_aircraft(arguments.seed, k, vehicle)
        measured = (measured_mass_properties(aircraft, arguments.seed, k)
                    if arguments.measured_mass_properties else NOMINAL)
        tasks.append(AircraftTask(f"#{k}", k, aircraft, parameters, measured, excite,
                                  condition, plan, vehicle))
    started = time.monotonic()
    with Campaign(campaign_options(arguments)) as campaign:
        rows = campaign.results(study_aircraft, tasks, "aircraft")
    for row in rows:
        print_row(row)
    totals = summary(rows)
    print(f"{totals['meet_targets']} of {totals['aircraft']} drawn aircraft meet the targets; "
          f"of those that do not, {totals['failing_flagged']} flagged by the check "
          f"(not: {', '.join(totals['failing_not_flagged']) or 'none'}); "
          f"{totals['meeting_flagged']} flagged that meet them")
    if arguments.json:
        arguments.json.write_text(json.dumps({
            "vehicle": vehicle, "count": arguments.count, "seed": arguments.seed,
            "parameters": list(parameters),
            "measured_mass_properties": (MEASUREMENT_ERROR if arguments.measured_mass_properties
                                         else None),
            "excitation": EXCITATION if excite else None,
            "calibration_plan": [path.name for path in plan] or None,
            "calibration_condition": condition,
            "draw": DRAW, "targets": {"fault_free_below_pct": targets.FAULT_FREE_BELOW_PCT,
                                      "rmse_share": targets.RMSE_SHARE,
                                      "detected_within_s": targets.DETECTED_WITHIN_S,
                                      "final_share": targets.FINAL_SHARE},
            "wall_time_s": round(time.monotonic() - started, 1),
            "summary": totals, "aircraft": rows}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
