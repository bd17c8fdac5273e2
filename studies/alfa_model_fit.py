#!/usr/bin/env python3
"""A vehicle's model held against real flights: ALFA's no-failure flights of the Carbon-Z.

    python -m studies.alfa_model_fit ALFA/ [--vehicle carbon_z] [--json FILE]

Reads every `*_no_failure` flight under the folder (ALFA's CSV export, the shipped
`carbon_z_alfa` airframe) onto a 0.2 s grid, and steps the vehicle's model from each logged
state with the autopilot's outputs as the surfaces and throttle and the autopilot's wind
estimate as the wind, through residual_node's generator (its defaults, no fault columns):
the residuals are what the logged accelerations do that the model does not predict. Per
residual channel it prints their RMS over each flight against the noise the simulator
assumes (the vehicle's noise model, filtered-wind suite, whose residuals carry turbulence
and sensor noise only).

Then, leaving one day out: the model calibration (estimation/model_calibration.py) fitted
on the other days' flights, its residual RMS on the left-out day's flights beside the shipped
model's. The logs have no angle of attack or sideslip and, from 2018-09-11 on, no airspeed:
the models fly the wind estimate throughout, and the air-data biases are not fitted
(PARAMETERS).

What the logs lack is filled, each said: latitude and longitude (ALFA's field near
Pittsburgh: they only set gravity), the altitude (390 m, the 2018-07-18 flight's vfr_hud
altitude, 390-398 m: it only sets the air density, 1 % per 100 m), the fuel (none), flap
(none), mixture and ignition (on), the rudder (0: the autopilot mixes it from the aileron,
an unknown sign), and the motor's speed, which no topic logs: the propeller's steady speed
at the logged throttle and the air-relative speed the wind estimate gives
(uav_aircraft.propeller.steady_rpm).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from uav_aircraft.airframe import load_airframe
from uav_aircraft.fdm import EFFECTIVE_THROTTLE, KG_PER_M3_PER_SLUG_PER_FT3, M_PER_FT, create_fdm
from uav_aircraft.flown_aircraft import NOMINAL, FlownAircraft
from uav_aircraft.propeller import Propeller
from uav_aircraft.vehicles import load_vehicle, vehicle_names
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_fault_estimator.estimation.model_calibration import SensorFlight, calibrate
from uav_fault_estimator.estimation.model_parameters import AIR_DATA_BIASES, DEFAULT_PARAMETERS
from uav_fault_estimator.estimation.noise_model import NoiseCalibration, load_noise_calibration
from uav_fault_estimator.estimation.prediction import residual_sampler
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.estimation.residuals import RESIDUAL_CHANNELS
from uav_fault_estimator.flight_logs.readers import read_log
from uav_fault_estimator.flight_logs.resample import LINEAR, detector_samples, resample
from uav_fault_estimator.flight_logs.streams import WIND

GRID_S = 0.2
FIELD_LATITUDE_DEG, FIELD_LONGITUDE_DEG = 40.44, -79.94
ALTITUDE_M = 390.0
PARAMETERS = tuple(name for name in DEFAULT_PARAMETERS if name not in AIR_DATA_BIASES)
FILTERED = "filtered_wind"
_STATE = {name: k for k, name in enumerate(STATE_CHANNELS)}
_CONTROL = {name: k for k, name in enumerate(CONTROL_CHANNELS)}


def day_of(flight_name: str) -> str:
    """The flight's day, from ALFA's folder name (carbonZ_<yyyy-mm-dd>-<hh-mm-ss>...)."""
    return flight_name.split("_")[1][:10]


def sensor_flight(folder: Path, vehicle: str) -> SensorFlight:
    """The log on the grid as a model calibration reads a flight, the gaps filled as the
    module says."""
    log = read_log(folder)
    airframe = load_airframe(load_vehicle("carbon_z").airframe_files["carbon_z_alfa"])
    inputs = detector_samples(log, airframe, GRID_S)
    times_s, state, controls = inputs.times_s, inputs.state.copy(), inputs.controls.copy()
    state[:, _STATE["latitude"]] = math.radians(FIELD_LATITUDE_DEG)
    state[:, _STATE["longitude"]] = math.radians(FIELD_LONGITUDE_DEG)
    state[:, _STATE["altitude"]] = ALTITUDE_M
    state[:, _STATE["fuel_mass"]] = 0.0
    for channel, value in (("flap", 0.0), ("rudder", 0.0), ("mixture", 1.0),
                           ("ignition", 1.0)):
        controls[:, _CONTROL[channel]] = value
    wind = np.column_stack([resample(log.streams[WIND], times_s, LINEAR),
                            np.zeros(times_s.size)])
    state[:, _STATE["engine_speed"]] = steady_engine_speed(state, controls, wind, vehicle)
    return SensorFlight(folder.name, times_s, state, controls, wind,
                        np.full((times_s.size, 3), np.nan))


def steady_engine_speed(state: np.ndarray, controls: np.ndarray, wind_ned_mps: np.ndarray,
                        vehicle: str) -> np.ndarray:
    """The motor speed [rpm] at which the propeller absorbs the power of the logged throttle
    (through the vehicle's FCS) at the air-relative speed of the ground velocity less the
    wind estimate; NaN where the throttle or velocity is missing."""
    model = load_vehicle(vehicle)
    fdm, propeller = create_fdm(model), Propeller.from_vehicle(model)
    fdm["ic/h-sl-ft"] = ALTITUDE_M / M_PER_FT
    fdm.run_ic()
    density = fdm["atmosphere/rho-slugs_ft3"] * KG_PER_M3_PER_SLUG_PER_FT3
    velocity = state[:, [_STATE[c] for c in ("velocity_north", "velocity_east", "velocity_down")]]
    airspeed_mps = np.linalg.norm(velocity - wind_ned_mps, axis=1)
    rpm = np.full(state.shape[0], np.nan)
    for k, (throttle, speed) in enumerate(zip(controls[:, _CONTROL["throttle"]], airspeed_mps,
                                               strict=True)):
        if np.isfinite(throttle) and np.isfinite(speed):
            fdm["fcs/throttle-cmd-norm"] = float(throttle)
            fdm.run_ic()
            rpm[k] = propeller.steady_rpm(fdm[EFFECTIVE_THROTTLE], float(speed), density)
    return rpm


def residual_rows(flight: SensorFlight, residual: ResidualSettings,
                  model: FlownAircraft) -> np.ndarray:
    """The valid residual rows (K, 6) residual_node's generator (its settings, no fault
    columns) gives on the flight with the model's copies."""
    sampler = residual_sampler(dataclasses.replace(residual, fault_names=()), model)
    rows = []
    for k, time_s in enumerate(flight.times_s):
        try:
            result = sampler.update(float(time_s), flight.states[k], flight.controls[k],
                                    flight.winds_ned_mps[k], None)
        except ValueError:
            continue
        if result is not None and result.valid.all():
            rows.append(result.residual)
    return np.array(rows).reshape(-1, len(RESIDUAL_CHANNELS))


def rms(rows: np.ndarray) -> list[float]:
    return [float(v) for v in np.sqrt(np.mean(rows**2, axis=0))] if rows.size else []


def filtered_noise(vehicle: str) -> NoiseCalibration:
    """The vehicle's filtered-wind noise for both suites: these flights fly no air data."""
    noise = load_noise_calibration(vehicle=vehicle)
    return NoiseCalibration({suite: noise.variances[FILTERED] for suite in noise.variances},
                            {suite: noise.correlations[FILTERED] for suite in noise.variances})


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, help="ALFA's flights (one folder per flight)")
    parser.add_argument("--vehicle", choices=vehicle_names(), required=True)
    parser.add_argument("--json", type=Path)
    arguments = parser.parse_args()
    started = time.monotonic()
    vehicle = arguments.vehicle
    flights = [sensor_flight(path, vehicle)
               for path in sorted(arguments.folder.glob("*_no_failure")) if path.is_dir()]
    assumed = [float(v) for v in np.sqrt(load_noise_calibration(vehicle=vehicle)
                                         .variances[FILTERED])]
    print("channels: " + ", ".join(RESIDUAL_CHANNELS) + " (m/s^2, rad/s^2)")
    print("assumed noise RMS: " + " ".join(f"{v:.3f}" for v in assumed))
    residual = ResidualSettings(vehicle=vehicle)
    shipped = {f.name: rms(residual_rows(f, residual, NOMINAL)) for f in flights}
    days = sorted({day_of(f.name) for f in flights})
    held_out = {}
    for day in days:
        fitted_on = [f for f in flights if day_of(f.name) != day]
        calibration = calibrate(fitted_on, PARAMETERS, residual,
                                filtered_noise(vehicle), log=lambda line: None)
        values = dict(zip(calibration.names, calibration.values.round(2).tolist(), strict=True))
        for flight in (f for f in flights if day_of(f.name) == day):
            held_out[flight.name] = {"day_left_out": day, "calibrated_rms": rms(
                residual_rows(flight, residual, calibration.aircraft)),
                "parameters": values}
    for flight in flights:
        print(f"{flight.name}: shipped "
              + " ".join(f"{v:.3f}" for v in shipped[flight.name]) + "; calibrated on the "
              "other days " + " ".join(f"{v:.3f}" for v in held_out[flight.name]
                                       ["calibrated_rms"]))
    wall_s = time.monotonic() - started
    print(f"{len(flights)} flights, {len(days)} days, in {wall_s:.0f} s")
    if arguments.json:
        arguments.json.write_text(json.dumps(
            {"vehicle": vehicle, "channels": list(RESIDUAL_CHANNELS),
             "assumed_noise_rms": assumed, "parameters_fitted": list(PARAMETERS),
             "flights": {f.name: {"duration_s": float(f.times_s[-1] - f.times_s[0]),
                                  "shipped_rms": shipped[f.name], **held_out[f.name]}
                         for f in flights}, "wall_s": wall_s}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
