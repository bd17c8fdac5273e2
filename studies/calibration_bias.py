#!/usr/bin/env python3
"""What the model calibration finds on the model's own aircraft: the method's bias.

    python -m studies.calibration_bias [--seeds 3] [--parameters A,B,...] [--json FILE]
        [--workers N]

The aircraft flown is the model itself (aerosonde.xml as shipped), so a calibration that
measured only the aircraft would find 0 in every parameter. Its three calibration flights
(random_aircraft.calibration_scenarios: 22, 25 and 28 m/s in winds of 5-6 m/s; --seeds sets
of seeds) are flown in each of CONDITIONS, which take away the turbulence, the sensor noise
or both, and calibrated with the default parameters (or --parameters). Per condition and
parameter: the mean over the seeds, the smallest and largest value, and the mean posterior
deviation. What the ideal condition finds is the model's own accuracy; what the others add
is what the flights' turbulence and sensor noise do to the fit, a bias every aircraft
calibrated from such flights carries. Conditions run one per worker (the campaign layer);
about 1.5 minutes each on one core.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np
from uav_aircraft.flown_aircraft import NOMINAL
from uav_fault_estimator.campaigns.campaign import Campaign, campaign_options, exit_on_failed_tasks
from uav_sim.scenario import Scenario

from studies.random_aircraft import (
    CONDITIONS,
    EXCITATION,
    calibrate_scenarios,
    calibration_scenarios,
    calibration_study_arguments,
)


@dataclasses.dataclass(frozen=True)
class BiasTask:
    """One calibration: the condition, the seed set (random_aircraft's aircraft index),
    the parameters fitted."""

    condition: str
    seed_set: int
    parameters: tuple[str, ...]
    excite: bool = False
    plan: tuple[Path, ...] = ()


def flights_in(condition: str, seed_set: int, excite: bool = False,
               plan: tuple[Path, ...] = ()) -> list[Scenario]:
    """The model's calibration flights of the seed set (with random_aircraft.EXCITATION
    when excite; the plan's scenario files instead where given), flown in the condition
    (random_aircraft.CONDITIONS)."""
    return calibration_scenarios(NOMINAL, seed_set, excite, condition, plan)


def calibrate_task(task: BiasTask) -> dict:
    """The task's calibration: per parameter its value and posterior deviation."""
    flights = flights_in(task.condition, task.seed_set, task.excite, task.plan)
    calibration, _, _ = calibrate_scenarios(flights, task.parameters)
    return {"condition": task.condition, "seed_set": task.seed_set,
            "seeds": [s.seed for s in flights],
            "values": {name: [round(float(v), 3), round(float(s), 3)] for name, v, s in zip(
                calibration.names, calibration.values, calibration.posterior_std, strict=True)}}


def summary(rows: list[dict], parameters: tuple[str, ...]) -> dict:
    """Per condition and parameter: mean, smallest, largest value over the seed sets and
    the mean posterior deviation [the parameter's unit]."""
    table = {}
    for condition in CONDITIONS:
        values = np.array([[row["values"][name][0] for name in parameters]
                           for row in rows if row["condition"] == condition])
        deviations = np.array([[row["values"][name][1] for name in parameters]
                               for row in rows if row["condition"] == condition])
        table[condition] = {name: {"mean": round(float(values[:, j].mean()), 2),
                                   "min": round(float(values[:, j].min()), 2),
                                   "max": round(float(values[:, j].max()), 2),
                                   "posterior_std": round(float(deviations[:, j].mean()), 2)}
                            for j, name in enumerate(parameters)}
    return table


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="seed sets per condition")
    arguments = calibration_study_arguments(parser)
    parameters = arguments.parameters
    tasks = [BiasTask(condition, seed_set, parameters, arguments.excite, arguments.plan)
             for condition in CONDITIONS
             for seed_set in range(arguments.seeds)]
    started = time.monotonic()
    with Campaign(campaign_options(arguments)) as campaign:
        rows = campaign.results(calibrate_task, tasks, "calibrations")
    table = summary(rows, parameters)
    print(f"{'parameter':<22}" + "".join(f"{c[:24]:>26}" for c in CONDITIONS))
    for name in parameters:
        print(f"{name:<22}" + "".join(
            f"{table[c][name]['mean']:>+9.2f} [{table[c][name]['min']:+.1f}, "
            f"{table[c][name]['max']:+.1f}]".rjust(26) for c in CONDITIONS))
    if arguments.json:
        arguments.json.write_text(json.dumps({
            "seed_sets": arguments.seeds, "parameters": list(parameters),
            "excitation": EXCITATION if arguments.excite else None,
            "calibration_plan": [path.name for path in arguments.plan] or None,
            "conditions": {name: {"turbulence": t, "sensor_noise": n}
                           for name, (t, n) in CONDITIONS.items()},
            "wall_time_s": round(time.monotonic() - started, 1),
            "summary": table, "calibrations": rows}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
