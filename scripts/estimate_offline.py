#!/usr/bin/env python3
"""The main job's chain without ROS: fly a scenario in the core simulator, make its
residuals and estimate its faults with the nodes' default parameters, print metrics.json's
table (no recording, no figures).

    python scripts/estimate_offline.py [SCENARIO.yaml] [--turbulence LEVEL] [--true-wind]
                                       [--json FILE]

The same numbers the ROS graph gives for the same scenario
(tests/uav_fault_estimator/chain/test_demo_run.py checks that), in a few seconds; for
tuning and for comparing turbulence levels. --true-wind gives the models the true wind
instead of the 10 s filtered one: what perfect wind knowledge would buy.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

from uav_fault_estimator.chain.offline import fly_and_estimate
from uav_fault_estimator.reporting import report
from uav_sim.scenario import (
    TURBULENCE_LEVELS,
    ScenarioError,
    default_scenario_path,
    load_scenario,
)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", type=Path, default=default_scenario_path())
    parser.add_argument("--turbulence", choices=TURBULENCE_LEVELS,
                        help="fly the scenario with this turbulence instead of its own")
    parser.add_argument("--true-wind", action="store_true",
                        help="give the models the true wind, not the filtered estimate")
    parser.add_argument("--json", type=Path, help="also write metrics.json here")
    arguments = parser.parse_args()
    try:
        scenario = load_scenario(arguments.scenario)
    except ScenarioError as error:
        print(f"estimate_offline.py: {' '.join(str(error).split())}", file=sys.stderr)
        return 2
    if arguments.turbulence:
        scenario = dataclasses.replace(scenario, wind=dataclasses.replace(
            scenario.wind, turbulence=arguments.turbulence))
    started = time.monotonic()
    estimates, seeded = fly_and_estimate(scenario, true_wind=arguments.true_wind)
    run = report.Run(estimates, seeded, duration_s=float(estimates.stamps_s[-1]),
                     wall_s=time.monotonic() - started)
    name = scenario.name + (f", {arguments.turbulence} turbulence"
                            if arguments.turbulence else "") + (
        ", true wind" if arguments.true_wind else "")
    metrics = report.run_metrics(run, name)
    if arguments.json:
        arguments.json.write_text(json.dumps(metrics, indent=2) + "\n")
    print(report.table(metrics))
    return 0


if __name__ == "__main__":
    sys.exit(main())
