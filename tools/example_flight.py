#!/usr/bin/env python3
"""Write the example flight that docs/flight_logs.md's commands run on from a clone.

    python tools/example_flight.py [--out examples/flights]

A simulated Aerosonde, the shipped aileron_loss scenario cut to DURATION_S, its ailerons
losing 90 % of their effect from ONSET_S on (an aileron failure), logged as a real aircraft's
MAVROS would log it (jittered instants: the IMU at 10 Hz, airspeed at 5 Hz, PWM outputs at
2.9 Hz by the shipped airframe aircraft/aerosonde/airframes/aerosonde_sim.yaml, ground
velocity at 4 Hz)
and exported in ALFA's processed layout: OUT/FLIGHT/FLIGHT-<topic>.csv, with the ground
truth ALFA gives, FLIGHT-failure_status-aileron.csv, from the onset on. The logs are
tests/helpers/simulated_logs.py's, the project's writer of simulated flight logs; the seed
is fixed, so that the same command writes the same flight. Run with scripts/env.sh sourced.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO_ROOT / "tests"))  # the writer of simulated logs: helpers/

from helpers import simulated_logs  # noqa: E402
from uav_aircraft.vehicles import load_vehicle  # noqa: E402
from uav_sim.paths import scenarios_dir  # noqa: E402
from uav_sim.scenario import load_scenario  # noqa: E402

FLIGHT = "aerosonde_sim_aileron_failure"  # ALFA's naming: what happened, last
DURATION_S = 80.0  # detector_node settles 30 s: 20 s tested before the onset less 5 s
ONSET_S = 55.0
SEED = 23  # the log instants' jitter and latencies
FAILURE_STATUS_PERIOD_S = 0.5  # ALFA's failure_status rate, about 2 Hz


def example_scenario():
    """The aileron_loss scenario cut to DURATION_S, its aileron loss moved to ONSET_S."""
    scenario = load_scenario(scenarios_dir() / "aileron_loss.yaml")
    (fault,) = scenario.faults
    return dataclasses.replace(scenario, duration_s=DURATION_S, faults=(
        dataclasses.replace(fault, start_s=ONSET_S),))


def write_failure_status(folder: Path) -> None:
    """FOLDER-failure_status-aileron.csv as ALFA writes it: a row (`%time` [ns] in the log's
    clock, data 1) every FAILURE_STATUS_PERIOD_S from the onset to the end."""
    steps = int((DURATION_S - ONSET_S) / FAILURE_STATUS_PERIOD_S) + 1
    times_ns = [simulated_logs.BAG_START_NS + round((ONSET_S + k * FAILURE_STATUS_PERIOD_S)
                                                    * 1e9) for k in range(steps)]
    (folder / f"{folder.name}-failure_status-aileron.csv").write_text(
        "%time,field.data\n" + "".join(f"{time_ns},1\n" for time_ns in times_ns))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO_ROOT / "examples" / "flights")
    arguments = parser.parse_args()
    airframe = load_vehicle("aerosonde").airframe_files["aerosonde_sim"]
    truth = simulated_logs.simulate_truth(example_scenario(), SEED, airframe)
    folder = arguments.out / FLIGHT
    with tempfile.TemporaryDirectory() as scratch:
        bag = Path(scratch) / f"{FLIGHT}.bag"
        simulated_logs.write_mavros_bag(bag, truth, SEED)
        simulated_logs.export_csv(bag, folder, simulated_logs.ALFA)
    write_failure_status(folder)
    sizes = {path.name: path.stat().st_size for path in sorted(folder.iterdir())}
    print(f"wrote {folder}: " + ", ".join(f"{name} ({size // 1024} KiB)"
                                          for name, size in sizes.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
