#!/usr/bin/env python3
"""Calibrate detector_node from fault-free flights (Blanke & Hansen, section II-III).

    python scripts/calibrate_detector.py [--vehicle NAME] [--flights 12] [--bags BAG ...]
                                         [--out FILE]

Flies the vehicle's fault-free scenario (its default flight: turbulence from the wind, noisy
sensors, air data) with other seeds and background winds of 20-25 % of its airspeed towards
directions 360/N degrees apart, samples it every sample_period_s, and fits: the RLS's initial
parameters and covariance, the parameters' fault-free mean and spread, and the Weibull
distributions of the GLRT statistic (per channel) and of the largest parameter deviation
(calibration_fit.calibrate). Writes the YAML that detector_node reads (default: the vehicle
folder's detector_calibration.yaml in this source tree), with the sample period, forgetting
factor, window and settling time it was made with (detection.calibration's defaults), for
which alone it holds: detector_node runs it with them.
Held-out flights for the false-alarm test use seeds from 201 (tests/detector). --bags
calibrates from recordings of fault-free flights instead (recorder_node's or demo.sh's bag/
folders: their /state and /controls), of the vehicle they say flew (their simulator's or
link's /diagnostics: recording.project_bag.recorded_vehicle; --vehicle for those that do not
say).

Exit status: 0 written; 1 the calibration failed; 2 a bad argument, or recordings of another
vehicle than --vehicle or of several (one line).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from uav_aircraft.paths import calibration_output_path
from uav_aircraft.vehicles import (
    DEFAULT_VEHICLE,
    DETECTOR_CALIBRATION_FILE,
    VehicleError,
    vehicle_names,
    vehicle_of_sources,
)
from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    CampaignOptions,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.chain.offline import (
    CALIBRATION_FIRST_SEED,
    CALIBRATION_FLIGHTS,
    describe_flights,
    fault_free_flights,
    fly_on_grid_each,
)
from uav_fault_estimator.detection.calibration import (
    DEFAULT_SAMPLE_PERIOD_S,
    simulated_airframe,
)
from uav_fault_estimator.detection.calibration_file import calibration_to_dict
from uav_fault_estimator.detection.calibration_fit import calibrate
from uav_fault_estimator.detection.generators import SHIPPED_GENERATORS, generator_names
from uav_fault_estimator.recording.project_bag import (
    RecordingError,
    flight_from_recording,
    project_typestore,
    recorded_vehicle,
)
from uav_fault_estimator.reporting.calibration_output import write_calibration


def simulated(count: int, vehicle: str, options: CampaignOptions) -> tuple[list, str]:
    """count fault-free flights of the vehicle flown now, where options say, and the
    calibration file's header saying which."""
    scenarios = fault_free_flights(count, CALIBRATION_FIRST_SEED, vehicle=vehicle)
    with Campaign(options) as campaign:
        flights = [flight.detector_flight for flight
                   in fly_on_grid_each(campaign, scenarios, DEFAULT_SAMPLE_PERIOD_S)]
    header = (f"# Written by scripts/calibrate_detector.py: {len(scenarios)} fault-free flights "
              f"of\n# {describe_flights(scenarios)}.\n")
    return flights, header


def recorded(bags: list[Path]) -> tuple[list, str]:
    """The flights of recordings, and the calibration file's header naming them."""
    typestore = project_typestore()
    flights = [flight_from_recording(bag, typestore, DEFAULT_SAMPLE_PERIOD_S) for bag in bags]
    header = ("# Written by scripts/calibrate_detector.py from the recordings "
              + ", ".join(str(bag) for bag in bags) + ".\n")
    return flights, header


def recordings_vehicle(bags: list[Path], given: str | None) -> str:
    """The vehicle the recordings say flew (vehicle_of_sources: given where none says);
    VehicleError or RecordingError, one line, otherwise."""
    typestore = project_typestore()
    return vehicle_of_sources({str(bag): recorded_vehicle(bag, typestore) for bag in bags},
                              given, say=lambda line: print(f"calibrate_detector.py: {line}"))


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicle", choices=vehicle_names(),
                        help=f"the aircraft (default: the one the --bags say flew, else "
                        f"{DEFAULT_VEHICLE}); refused where the --bags say another")
    parser.add_argument("--flights", type=int, default=CALIBRATION_FLIGHTS)
    parser.add_argument("--bags", type=Path, nargs="+",
                        help="recordings of fault-free flights to calibrate from, not flying")
    parser.add_argument("--out", type=Path,
                        help="default: the vehicle's folder in this source tree")
    parser.add_argument("--generators", type=generator_names, default=SHIPPED_GENERATORS,
                        help="comma-separated (detection/generators.py; default "
                             + ",".join(SHIPPED_GENERATORS) + ")")
    add_campaign_arguments(parser)
    arguments = parser.parse_args()
    try:
        vehicle = (recordings_vehicle(arguments.bags, arguments.vehicle) if arguments.bags
                   else arguments.vehicle or DEFAULT_VEHICLE)
    except (VehicleError, RecordingError) as error:
        print(f"calibrate_detector.py: {error}", file=sys.stderr)
        return 2
    out = arguments.out or calibration_output_path(vehicle, DETECTOR_CALIBRATION_FILE)
    started = time.monotonic()
    try:
        flights, header = (recorded(arguments.bags) if arguments.bags
                           else simulated(arguments.flights, vehicle,
                                          campaign_options(arguments)))
        calibration = calibrate(flights, airframe=simulated_airframe(vehicle),
                                generators=arguments.generators)
    except (ValueError, FileNotFoundError) as error:
        print(f"calibrate_detector.py: {error}", file=sys.stderr)
        return 1
    header += "# Valid for the sample period, forgetting factor and windows below only.\n"
    write_calibration(out, header, calibration_to_dict(calibration),
                      f"{len(flights)} flights", time.monotonic() - started)
    return 0


if __name__ == "__main__":
    sys.exit(main())
