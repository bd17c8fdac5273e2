#!/usr/bin/env python3
"""Calibrate the estimator's residual noise (Q) from fault-free flights, per sensor suite.

    python scripts/calibrate_estimator.py [--vehicle aerosonde] [--flights 4] [--out FILE]

Flies the vehicle's fault-free scenario (its default flight in its turbulence from the wind,
noisy sensors) with seeds from 301 and background winds of 20-25 % of its airspeed towards
directions 360/N degrees apart, once per sensor suite (air data with vanes, a pitot without
them, none: the paper's filtered wind only), through residual_node's residual generator
with its default parameters, and writes each suite's per-channel variances and one-step
correlations of the residuals (noise_model.py) to the YAML that mhe_node reads (default:
the vehicle folder's residual_noise.yaml in this source tree). Other seeds than the
detector's (101-112) and its held-out flights (201-212), and than the default scenario's 7
that the estimator is judged on.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

from uav_aircraft.paths import calibration_output_path
from uav_aircraft.vehicles import DEFAULT_VEHICLE, NOISE_FILE, vehicle_names
from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.chain.offline import (
    describe_flights,
    fault_free_flights,
    fault_free_residuals,
)
from uav_fault_estimator.estimation.noise_model import SUITE_SENSORS, fit_noise
from uav_fault_estimator.reporting.calibration_output import write_calibration
from uav_sim.scenario import SensorSuite

FIRST_SEED = 301


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicle", choices=vehicle_names(), default=DEFAULT_VEHICLE)
    parser.add_argument("--flights", type=int, default=4)
    parser.add_argument("--out", type=Path,
                        help="default: the vehicle's folder in this source tree")
    add_campaign_arguments(parser)
    arguments = parser.parse_args()
    started = time.monotonic()
    base = fault_free_flights(arguments.flights, FIRST_SEED, vehicle=arguments.vehicle)
    scenarios = [dataclasses.replace(s, sensors=SensorSuite(air_data=air_data, vanes=vanes))
                 for air_data, vanes in SUITE_SENSORS.values() for s in base]
    with Campaign(campaign_options(arguments)) as campaign:
        residuals = campaign.results(fault_free_residuals, scenarios, "fault-free flights")
    count = len(base)
    calibration = fit_noise({suite: residuals[k * count:(k + 1) * count]
                             for k, suite in enumerate(SUITE_SENSORS)})
    header = (f"# Written by scripts/calibrate_estimator.py: residuals of {count} fault-free "
              f"flights per sensor suite of\n# {describe_flights(base)}.\n"
              "# Valid for residual_node's default parameters.\n")
    out = arguments.out or calibration_output_path(arguments.vehicle, NOISE_FILE)
    write_calibration(out, header, calibration.to_dict(arguments.vehicle),
                      f"{count} flights per suite", time.monotonic() - started)
    return 0


if __name__ == "__main__":
    sys.exit(main())
