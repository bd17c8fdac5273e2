#!/usr/bin/env python3
"""Benchmark of the core simulator: wall time and real-time factor of a scenario.

    python -m benchmarks.bench_sim [SCENARIO.yaml] [--repeat N]

Prints the start-up (trim and engine spin-up) and flight times, and the real-time factor
(simulated seconds per wall second) of the Simulation alone, without ROS.
"""

from __future__ import annotations

import argparse
import time

from uav_sim.scenario import default_scenario_path, load_scenario
from uav_sim.simulation import Simulation


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default=str(default_scenario_path()))
    parser.add_argument("--repeat", type=int, default=3)
    arguments = parser.parse_args()
    scenario = load_scenario(arguments.scenario)
    print(f"scenario '{scenario.name}': {scenario.duration_s:g} s at 20 Hz, JSBSim at 480 Hz")
    for run in range(arguments.repeat):
        started = time.perf_counter()
        simulation = Simulation(scenario)
        ready = time.perf_counter()
        while not simulation.finished:
            simulation.step()
        done = time.perf_counter()
        print(
            f"run {run + 1}: start-up {ready - started:.3f} s, flight {done - ready:.2f} s, "
            f"real-time factor {scenario.duration_s / (done - ready):.1f}"
        )


if __name__ == "__main__":
    main()
