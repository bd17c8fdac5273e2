#!/usr/bin/env python3
"""Benchmark of the residual core: cost per sensor sample and per published residual.

    python -m benchmarks.bench_residuals [SCENARIO.yaml] [--seconds S]

Flies the scenario's first S seconds in the core Simulation, records the samples, then
times ResidualGenerator.update alone on them with residual_node's defaults (JSBSim
prediction copies: the nominal one and one per fault of the paper's four, and one per wind
error axis when wind_error_step_mps is set; S recomputed every 0.5 s). A residual is
published every 0.5 s, i.e. every 10 samples at 20 Hz, so its cost is the sum over those
10 samples.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from uav_fault_estimator.estimation.prediction import residual_generator
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_sim.scenario import default_scenario_path, load_scenario
from uav_sim.simulation import Simulation


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default=str(default_scenario_path()))
    parser.add_argument("--seconds", type=float, default=120.0)
    arguments = parser.parse_args()
    simulation = Simulation(load_scenario(arguments.scenario))
    samples = [simulation.sample()]
    while simulation.time_s < arguments.seconds - 0.5 * simulation.period_s:
        samples.append(simulation.step())
    settings = ResidualSettings()
    generator = residual_generator(settings)
    costs_s = np.empty(len(samples))
    for index, sample in enumerate(samples):
        started = time.perf_counter()
        generator.update(sample.time_s, sample.state, sample.controls,
                         sample.wind_filtered_ned_mps)
        costs_s[index] = time.perf_counter() - started
    per_published_s = costs_s[1:].reshape(
        -1, round(settings.update_period_s / simulation.period_s))
    per_published_s = per_published_s.sum(axis=1)
    micro = 1e6
    print(f"{len(samples)} samples at 20 Hz, S columns {len(generator.column_names)}, "
          f"{len(per_published_s)} residuals published")
    print(f"per sensor sample:     median {micro * np.median(costs_s):.0f} us, "
          f"p99 {micro * np.percentile(costs_s, 99):.0f} us, max {micro * costs_s.max():.0f} us")
    print(f"per published residual: median {micro * np.median(per_published_s):.0f} us, "
          f"max {micro * per_published_s.max():.0f} us")
    print(f"core load at 20 Hz: {100 * costs_s.mean() * 20:.2f} % of one core")


if __name__ == "__main__":
    main()
