#!/usr/bin/env python3
"""Calibrate the prediction model from recordings of fault-free flights.

    python scripts/calibrate_model.py RECORDING... --out MODEL.yaml [--vehicle NAME]
        [--parameters A,B,...] [--measured AIRCRAFT.yaml] [--strict]
        [--airframe FILE] [--fuel-mass-kg KG]

RECORDING: a rosbag2 folder (demo.sh's DIR/bag, bringup's or recorder_node's) with /state,
/controls, /wind/filtered and, where the aircraft has them, /air_data of a flight with no
fault, flown by the vehicle: best the flights of the vehicle's calibration plan (its
aircraft folder's calibration_plan/: system-identification manoeuvres). Or the autopilot's
own log of such a flight: an ArduPilot DataFlash log (.bin) or a PX4 ULog (.ulg)
(flight_logs/calibration_logs.py: which message gives which column), its PWM outputs mapped
to the surfaces by the airframe FILE (default: the vehicle's only airframe file), with the
fuel mass KG on board (no autopilot logs it; default: what the vehicle's model carries).
The vehicle is the one the recordings say flew (their simulator's or link's /diagnostics:
recording.project_bag.recorded_vehicle); --vehicle names it for those that do not say
(autopilot logs; default aerosonde), and one that disagrees with them is refused. Identifies the
model's parameters (default: model_parameters.DEFAULT_PARAMETERS; any aerodynamic
coefficient of the vehicle's XML by name or all of them as `coefficients`, mass_scale,
thrust_scale, inertia_{x,y,z}_scale, cg_{x,y,z}_cm, airspeed_scale, angle_of_attack_deg,
sideslip_deg) so that the models fit the flights' accelerations
(estimation/model_calibration.py); prints each with its posterior deviation and the flights
that inform it, and the pairs the flights cannot separate with the manoeuvres that would
(estimation/identifiability.py); then checks the fit (estimation/calibration_check.py: the
weighted residual, parameters pushed beyond two prior deviations, a residual channel with a
structured remainder in a flight regime) and prints a WARN line for each finding, naming
what it suggests; writes MODEL.yaml for residual_node's model_calibration_file (demo.sh
--model-calibration MODEL.yaml) and, beside it, MODEL.noise.yaml: the residual noise of the
calibrated model on the same flights, per sensor suite (a suite none of them flew, such as
the air data of logs without vanes, the shipped one's), for mhe_node's
noise_calibration_file (calibrate_estimator.py's file, made from these flights instead of
simulated ones; MODEL.yaml names it, and demo.sh passes both); and ends with a line saying
whether the check passed.

AIRCRAFT.yaml: what was measured of the aircraft on the ground, as a scenario's `aircraft:`
block under the key `aircraft` (say cg_offset_m from a balance, inertia_scale from a
pendulum): the fit starts from it and holds what it does not fit there. The flights cannot
tell the CG along x and z or the inertias from the coefficients (docs/model_calibration.md),
and a fault's signature depends on them: measure them where you can.

Exit status: 0 written, the check passed; 1 the least squares did not solve, or --strict and
the check warned (nothing written); 2 a bad argument or recording, or recordings of another
vehicle than --vehicle or of several (one line each); 3 written, but the check warned.
"""

from __future__ import annotations

import argparse
import functools
import sys
import time
from pathlib import Path

import numpy as np
from uav_aircraft.airframe import load_airframe
from uav_aircraft.fdm import fuel_on_board_kg
from uav_aircraft.flown_aircraft import NOMINAL
from uav_aircraft.vehicle_parameter import VEHICLE_FUEL_KG
from uav_aircraft.vehicles import DEFAULT_VEHICLE, load_vehicle, vehicle_names, vehicle_of_sources
from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.estimation.calibration_check import check_calibration
from uav_fault_estimator.estimation.identifiability import (
    informing_flights,
    separating_manoeuvres,
)
from uav_fault_estimator.estimation.model_calibration import (
    CalibrationError,
    SensorFlight,
    calibrate,
)
from uav_fault_estimator.estimation.model_file import calibration_dict, load_measured_aircraft
from uav_fault_estimator.estimation.model_parameters import DEFAULT_PARAMETERS, parameter_list
from uav_fault_estimator.estimation.noise_model import (
    NoiseCalibration,
    fit_noise,
    load_noise_calibration,
)
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.flight_logs.calibration_logs import LOG_SUFFIXES, sensor_flight_from_log
from uav_fault_estimator.recording.project_bag import (
    RecordingError,
    project_typestore,
    recorded_vehicle,
    sensor_flight_from_recording,
)
from uav_fault_estimator.reporting.calibration_output import write_calibration

INSEPARABLE = 0.9  # |posterior correlation| from which a pair is said to be hard to separate
EXIT_CHECK_WARNED = 3  # written, but the fit's check warned


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recordings", nargs="+", type=Path, metavar="RECORDING")
    parser.add_argument("--out", type=Path, required=True, metavar="MODEL.yaml")
    parser.add_argument("--vehicle", choices=vehicle_names(),
                        help="the aircraft flown, where the recordings do not say it "
                        f"(default: {DEFAULT_VEHICLE}); refused where they say another")
    parser.add_argument("--parameters", default=",".join(DEFAULT_PARAMETERS),
                        help="comma-separated names (default: %(default)s)")
    parser.add_argument("--measured", type=Path, metavar="AIRCRAFT.yaml",
                        help="the aircraft as measured on the ground (`aircraft:` block)")
    parser.add_argument("--strict", action="store_true",
                        help="a warning of the fit's check is an error: nothing is written")
    parser.add_argument("--airframe", type=Path, metavar="FILE",
                        help="the servo mapping of the logs' outputs (default: the vehicle's "
                        "only airframe file)")
    parser.add_argument("--fuel-mass-kg", type=float, default=VEHICLE_FUEL_KG, metavar="KG",
                        help="the fuel on board during the logs' flights (default: what the "
                        "vehicle's model carries)")
    add_campaign_arguments(parser)
    arguments = parser.parse_args()
    started = time.monotonic()
    try:
        vehicle = vehicle_of_sources(_said_vehicles(arguments.recordings), arguments.vehicle,
                                     say=lambda line: print(f"calibrate_model.py: {line}"))
        names = parameter_list(arguments.parameters, load_vehicle(vehicle))
        measured = (load_measured_aircraft(arguments.measured, vehicle) if arguments.measured
                    else NOMINAL)
        flights = _load_flights(arguments.recordings, vehicle, arguments.airframe,
                                fuel_on_board_kg(arguments.fuel_mass_kg, load_vehicle(vehicle)))
    except (ValueError, RecordingError) as error:
        print(f"calibrate_model.py: {error}", file=sys.stderr)
        return 2
    minutes = sum(f.times_s[-1] - f.times_s[0] for f in flights) / 60.0
    print(f"{len(flights)} flights, {minutes:.1f} min; parameters {', '.join(names)}")
    noise = load_noise_calibration(vehicle=vehicle)
    try:
        with Campaign(campaign_options(arguments)) as campaign:
            calibration = calibrate(
                flights, names, ResidualSettings(vehicle=vehicle), noise,
                map_flights=functools.partial(campaign.results, name="recorded flights"),
                measured=measured)
    except CalibrationError as error:
        print(f"calibrate_model.py: {error}", file=sys.stderr)
        return 1
    _print_calibration(calibration, [f.name for f in flights])
    warnings = check_calibration(calibration, flights, noise)
    for warning in warnings:
        print(f"WARN {warning.text}")
    if warnings and arguments.strict:
        print(f"calibrate_model.py: --strict and {len(warnings)} warnings of the fit's check: "
              f"{arguments.out} not written", file=sys.stderr)
        return 1
    noise_path = arguments.out.with_suffix(".noise.yaml")
    sources = f"{len(flights)} recorded fault-free flights ({minutes:.1f} min): " + ", ".join(
        f.name for f in flights)
    write_calibration(noise_path, f"# Written by scripts/calibrate_model.py: residuals of the "
                      f"calibrated model ({arguments.out.name}) on\n# {sources}.\n",
                      _fitted_noise(calibration.residuals, noise).to_dict(vehicle),
                      "the same flights", time.monotonic() - started)
    write_calibration(arguments.out, f"# Written by scripts/calibrate_model.py from {sources}."
                      "\n# For residual_node's model_calibration_file.\n",
                      calibration_dict(calibration, vehicle, [f.name for f in flights],
                                       noise_path.name),
                      f"{len(flights)} flights", time.monotonic() - started)
    written = f"{arguments.out} and {noise_path.name}"
    if warnings:
        print(f"check failed: {len(warnings)} warnings (the WARN lines above); {written} "
              "written all the same: read the warnings before flying the model")
        return EXIT_CHECK_WARNED
    print(f"check passed: the model fits the flights; {written} written")
    return 0


def _said_vehicles(recordings: list[Path]) -> dict[str, str | None]:
    """The vehicle each recording says flew (recorded_vehicle; None for an autopilot's log,
    which does not say, and for a recording that cannot be read: its loading says why)."""
    typestore = project_typestore()
    said = {}
    for path in recordings:
        try:
            said[str(path)] = (None if path.suffix.lower() in LOG_SUFFIXES
                               else recorded_vehicle(path, typestore))
        except RecordingError:
            said[str(path)] = None
    return said


def _load_flights(recordings: list[Path], vehicle: str, airframe: Path | None,
                  fuel_mass_kg: float) -> list[SensorFlight]:
    """Each RECORDING as a calibration reads it: an autopilot's log (.bin, .ulg) through the
    airframe file (None: the vehicle's only one) with fuel_mass_kg [kg] on board, else a
    rosbag2 folder. ValueError or RecordingError (one line) for one that cannot be read."""
    logs = [path for path in recordings if path.suffix.lower() in LOG_SUFFIXES]
    servo_map = load_airframe(airframe or load_vehicle(vehicle).only_airframe_file()) \
        if logs else None
    typestore = project_typestore()
    return [sensor_flight_from_log(path, servo_map, fuel_mass_kg=fuel_mass_kg) if path in logs
            else sensor_flight_from_recording(path, typestore) for path in recordings]


def _fitted_noise(residuals: dict[str, list[np.ndarray]],
                  shipped: NoiseCalibration) -> NoiseCalibration:
    """fit_noise of the calibrated model's residuals (per suite, each flight's (K, 6)) for
    each suite the flights flew; a suite none flew keeps the shipped noise model's values (an
    autopilot's log has no vanes: its flights fly the wind estimate alone), so that mhe_node
    takes the file."""
    fitted = fit_noise({suite: flights for suite, flights in residuals.items()
                        if sum(len(flight) for flight in flights)})
    return NoiseCalibration({**shipped.variances, **fitted.variances},
                            {**shipped.correlations, **fitted.correlations})


def _print_calibration(calibration, flight_names: list[str]) -> None:
    """Each parameter with its posterior deviation and the flights that inform it (by
    number), the worst-correlated pairs, and for those hardly separated the manoeuvres that
    would separate them."""
    for number, name in enumerate(flight_names, 1):
        print(f"flight {number}: {name}")
    informed = informing_flights(calibration.flight_posterior_std, calibration.prior_std,
                                 [str(number) for number in range(1, len(flight_names) + 1)])
    print(f"{'parameter':<22}{'value':>9}{'+-':>8}  unit  (prior +- deviation)  informed by")
    for name, unit, value, posterior, mean, prior, flights in zip(
            calibration.names, calibration.units, calibration.values, calibration.posterior_std,
            calibration.prior_mean, calibration.prior_std, informed, strict=True):
        print(f"{name:<22}{value:>9.3f}{posterior:>8.3f}  {unit:<4}  ({mean:g} +- {prior:g})"
              f"  {', '.join(flights) or 'no flight: its prior holds it'}")
    print(f"{calibration.steps} Gauss-Newton steps, reduced chi-square "
          f"{calibration.reduced_chi_square:.3f}")
    for first, second, value in calibration.worst_correlations():
        separated = abs(value) < INSEPARABLE
        print(f"  correlation {first} / {second}: {value:+.3f} (" + (
            "separated)" if separated else "hardly separated: the flights fix a combination "
            "of the two, the prior the split; to separate them fly "
            + "; and ".join(separating_manoeuvres(first, second)) + ")"))


if __name__ == "__main__":
    sys.exit(main())
