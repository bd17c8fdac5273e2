#!/usr/bin/env python3
"""What the estimator can see, with which sensors, in which turbulence (a benchmark).

    python -m studies.detectability [--seeds 5] [--json FILE]

For each sensor suite (the paper's 10 s filtered wind only; air data on board) and each
turbulence (none, from_wind, light, moderate), flies `--seeds` variants of the shipped
default and fault_free scenarios (turbulence and noise seeds from 401, background winds of
5-6 m/s towards directions 360/seeds degrees apart) through the offline chain
(uav_fault_estimator.chain.offline: the nodes' default parameters, the calibrated noise of the
suite) and prints, per fault:

- fault-free: the largest estimate after settle_s over all flights, i.e. the smallest
  detection threshold with no false alarm on these flights, and the largest after 60 s
  (the start-up transient over);
- faulted (the default faults): the RMS error after settle_s (mean and worst over the
  flights) and the detection delay at the default threshold (worst; "-" if missed in any).

Flights run one process per core; about 10 minutes on the 2-core machine at 5 seeds.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np
from uav_common.channels import DETECTION_THRESHOLD_PCT as THRESHOLD_PCT
from uav_common.channels import PAPER_FAULT_NAMES
from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.chain.offline import fly_and_estimate, wind_variant
from uav_fault_estimator.estimation.estimator_step import SETTLE_S
from uav_fault_estimator.estimation.noise_model import SUITE_SENSORS
from uav_fault_estimator.reporting.metrics import fault_metrics
from uav_sim.scenario import Scenario, SensorSuite, default_scenario_path, load_scenario

TURBULENCES = ("none", "from_wind", "light", "moderate")
FIRST_SEED = 401        # other seeds than the calibrations' (101-112, 201-212, 301-304)
START_S = 60.0          # after the start-up transient (also printed: where the largest are)


def flights(seeds: int) -> list[tuple[str, str, bool, Scenario]]:
    """(suite, turbulence, faulted, scenario) of every flight of the study."""
    shipped = default_scenario_path()
    bases = {True: load_scenario(shipped), False: load_scenario(shipped.parent / "fault_free.yaml")}
    table = []
    for suite, (air_data, vanes) in SUITE_SENSORS.items():
        for turbulence in TURBULENCES:
            for faulted, base in bases.items():
                for k in range(seeds):
                    scenario = wind_variant(base, FIRST_SEED + k, 360.0 * k / seeds,
                                            5.0 + 0.25 * k)
                    scenario = dataclasses.replace(
                        scenario, sensors=SensorSuite(air_data=air_data, vanes=vanes),
                        wind=dataclasses.replace(scenario.wind, turbulence=turbulence))
                    table.append((suite, turbulence, faulted, scenario))
    return table


def figures(scenario: Scenario) -> dict:
    """One flight's metrics: per fault its rmse, delay and largest settled estimate."""
    estimates, seeded = fly_and_estimate(scenario)
    faults, _ = fault_metrics(estimates, seeded, SETTLE_S, THRESHOLD_PCT)
    settled = estimates.stamps_s >= SETTLE_S
    largest = estimates.values_pct[settled].max(axis=0)
    later = estimates.values_pct[estimates.stamps_s >= START_S].max(axis=0)
    return {name: {**faults[name], "largest_pct": float(largest[j]),
                   "largest_after_start_pct": float(later[j])}
            for j, name in enumerate(estimates.names)}


def summarise(results: list[tuple[str, str, bool, dict]]) -> dict:
    """Per suite and turbulence: per fault the fault-free largest estimate (all flights),
    the faulted rmse mean and worst, and the worst delay (None if missed in any flight)."""
    summary: dict = {}
    for suite in SUITE_SENSORS:
        for turbulence in TURBULENCES:
            cell = [(faulted, f) for s, t, faulted, f in results if (s, t) == (suite, turbulence)]
            entry = {}
            for name in PAPER_FAULT_NAMES:
                free = [f[name]["largest_pct"] for faulted, f in cell if not faulted]
                later = [f[name]["largest_after_start_pct"] for faulted, f in cell
                         if not faulted]
                rmse = [f[name]["rmse_pct"] for faulted, f in cell if faulted]
                delays = [f[name]["detection_delay_s"] for faulted, f in cell if faulted]
                entry[name] = {
                    "fault_free_largest_pct": round(max(free), 2),
                    "fault_free_largest_after_start_pct": round(max(later), 2),
                    "rmse_mean_pct": round(float(np.mean(rmse)), 2),
                    "rmse_worst_pct": round(max(rmse), 2),
                    "delay_worst_s": None if None in delays else max(delays),
                }
            summary.setdefault(suite, {})[turbulence] = entry
    return summary


def print_table(summary: dict, seeds: int) -> None:
    names = ", ".join(n.replace("_wing", "").replace("_", " ") for n in PAPER_FAULT_NAMES)
    print(f"\n{seeds} flights per cell, fault-free and faulted; per fault: {names}")
    print(f"| suite | turbulence | fault-free largest estimate [%] | same after {START_S:g} s "
          "[%] | rmse mean (worst) [%] | worst delay [s] |")
    print("|---|---|---|---|---|---|")
    for suite, rows in summary.items():
        for turbulence, entry in rows.items():
            values = entry.values()
            largest = " / ".join(f"{v['fault_free_largest_pct']:.2f}" for v in values)
            later = " / ".join(f"{v['fault_free_largest_after_start_pct']:.2f}" for v in values)
            rmse = " / ".join(f"{v['rmse_mean_pct']:.2f} ({v['rmse_worst_pct']:.2f})"
                              for v in values)
            delay = " / ".join("-" if v["delay_worst_s"] is None else f"{v['delay_worst_s']:g}"
                               for v in values)
            print(f"| {suite} | {turbulence} | {largest} | {later} | {rmse} | {delay} |")


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--json", type=Path, help="also write the summary here")
    add_campaign_arguments(parser)
    arguments = parser.parse_args()
    started = time.monotonic()
    table = flights(arguments.seeds)
    with Campaign(campaign_options(arguments)) as campaign:
        measured = campaign.results(figures, [scenario for *_, scenario in table],
                                    "detectability flights")
    summary = summarise([(*row[:3], f) for row, f in zip(table, measured, strict=True)])
    print_table(summary, arguments.seeds)
    print(f"\n{len(table)} flights in {time.monotonic() - started:.0f} s")
    if arguments.json:
        arguments.json.write_text(json.dumps(
            {"seeds": arguments.seeds, "first_seed": FIRST_SEED, "settle_s": SETTLE_S,
             "start_s": START_S,
             "threshold_pct": THRESHOLD_PCT, "summary": summary}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
