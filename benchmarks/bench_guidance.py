#!/usr/bin/env python3
"""Benchmark of the waypoint guidance: how closely each method flies the default route,
and what each leaves the estimator.

    python -m benchmarks.bench_guidance [--json FILE]

Flies the fault_free scenario (the default route and seed, no fault) with the course vector
field and with the MPC guidance, in calm air and in wind of 20 % (the paper's) and 25 % of
the airspeed with its turbulence (from_wind). Per flight: the cross-track error's RMS and
largest after the first SETTLE_TRACK_S, the corners passed (a flight that turned back along
a leg passes fewer), and for MPC the QP's solve time (ProxSuite's own timing; median, p99),
the largest yaw rate the solver planned over its limit and the steps flown on the vector
field. Then, per method, the fault_free scenario in the paper's wind with the seeds the
estimator was not tuned on (HELD_OUT_SEEDS) through the offline chain: the largest
fault-free estimate after the metrics' SETTLE_S, per flight, and how many reach the
detection threshold. Prints a line per flight and per method; --json writes them. About
4 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path

import numpy as np
from uav_common.channels import DETECTION_THRESHOLD_PCT
from uav_fault_estimator.campaigns.campaign import (
    Campaign,
    CampaignOptions,
    add_campaign_arguments,
    campaign_options,
    exit_on_failed_tasks,
)
from uav_fault_estimator.chain.offline import fly_and_estimate
from uav_fault_estimator.estimation.estimator_step import SETTLE_S
from uav_sim.guidance import route_errors
from uav_sim.mpc_guidance import MpcGuidance
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import Scenario, load_scenario
from uav_sim.simulation import Simulation

SETTLE_TRACK_S = 10.0  # the climb onto the first leg from the start is not tracking
WIND_FRACTIONS = (0.0, 0.20, 0.25)  # of the airspeed; 0.20 is the paper's
METHODS = ("vector_field", "mpc")
HELD_OUT_SEEDS = range(11, 23)  # fault-free flights the estimator was not tuned on


def in_wind(scenario: Scenario, fraction: float) -> Scenario:
    """The scenario in wind of fraction of its airspeed, blowing the way its wind blows,
    with turbulence from that wind; calm air (no turbulence) at 0."""
    wind = scenario.wind
    if fraction == 0.0:
        return dataclasses.replace(scenario, wind=dataclasses.replace(
            wind, north_mps=0.0, east_mps=0.0, down_mps=0.0, turbulence="none"))
    scale = fraction * scenario.initial.airspeed_mps / math.hypot(wind.north_mps, wind.east_mps)
    return dataclasses.replace(scenario, wind=dataclasses.replace(
        wind, north_mps=scale * wind.north_mps, east_mps=scale * wind.east_mps,
        turbulence="from_wind"))


def fly(scenario: Scenario) -> dict:
    """One flight's tracking figures (the module's docstring)."""
    simulation = Simulation(scenario)
    positions, times_s = [], []
    while not simulation.finished:
        sample = simulation.step()
        positions.append(sample.position_ne_m)
        times_s.append(sample.time_s)
    errors, corners = route_errors(scenario.waypoints_ne_m, np.array(positions))
    errors = errors[np.array(times_s) >= SETTLE_TRACK_S]
    figures = {"cross_track_rms_m": float(np.sqrt(np.mean(errors ** 2))),
               "cross_track_largest_m": float(np.max(np.abs(errors))), "corners": corners}
    guidance = simulation.guidance
    if isinstance(guidance, MpcGuidance):
        figures |= {"solve_ms_median": float(np.median(guidance.solve_times_ms)),
                    "solve_ms_p99": float(np.percentile(guidance.solve_times_ms, 99)),
                    "solves": len(guidance.solve_times_ms),
                    "largest_yaw_rate_over_limit": guidance.largest_command_ratio,
                    "fallbacks": guidance.fallbacks}
    return figures


def largest_fault_free_estimate_pct(scenario: Scenario) -> float:
    """The largest fault estimate [%] of the fault-free scenario after SETTLE_S, through
    the offline chain (the estimator's defaults)."""
    estimates, _ = fly_and_estimate(scenario)
    return float(estimates.values_pct[estimates.stamps_s >= SETTLE_S].max())


def estimator_margins(base: Scenario, options: CampaignOptions) -> list[dict]:
    """Per method, the largest fault-free estimate of each held-out seed's flight, flown
    where options say."""
    cases = [(method, seed) for method in METHODS for seed in HELD_OUT_SEEDS]
    with Campaign(options) as campaign:
        largest = campaign.results(largest_fault_free_estimate_pct, [
            dataclasses.replace(base, seed=seed, guidance=dataclasses.replace(
                base.guidance, method=method)) for method, seed in cases], "held-out flights")
    margins = []
    for method in METHODS:
        values = [value for (flown, _), value in zip(cases, largest, strict=True)
                  if flown == method]
        margins.append({"method": method, "seeds": list(HELD_OUT_SEEDS),
                        "largest_estimate_pct": values,
                        "mean_largest_pct": float(np.mean(values)),
                        "reaching_threshold": sum(v >= DETECTION_THRESHOLD_PCT for v in values)})
    return margins


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, help="write the figures here")
    add_campaign_arguments(parser)  # the estimator's margins; the timed flights fly here
    arguments = parser.parse_args()
    base = dataclasses.replace(load_scenario(scenarios_dir() / "fault_free.yaml"), faults=())
    flights = []
    for fraction in WIND_FRACTIONS:
        for method in METHODS:
            scenario = dataclasses.replace(in_wind(base, fraction), guidance=dataclasses.replace(
                base.guidance, method=method))
            figures = {"wind_pct": round(100 * fraction), "method": method,
                       **fly(scenario)}
            flights.append(figures)
            print(" ".join(f"{key} {value:.4g}" if isinstance(value, float)
                           else f"{key} {value}" for key, value in figures.items()), flush=True)
    margins = estimator_margins(base, campaign_options(arguments))
    for margin in margins:
        print(f"{margin['method']}: largest fault-free estimate per held-out flight [%] "
              + " ".join(f"{value:.2f}" for value in margin["largest_estimate_pct"])
              + f"; mean {margin['mean_largest_pct']:.2f}, "
              f"{margin['reaching_threshold']} reaching {DETECTION_THRESHOLD_PCT:g} %",
              flush=True)
    if arguments.json:
        arguments.json.write_text(json.dumps(
            {"scenario": base.name, "duration_s": base.duration_s, "seed": base.seed,
             "settle_s": SETTLE_TRACK_S, "flights": flights,
             "estimator_settle_s": SETTLE_S, "threshold_pct": DETECTION_THRESHOLD_PCT,
             "estimator": margins}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
