#!/usr/bin/env python3
"""What a pitot without vanes costs the fault estimates, beside what the physics allows.

    python -m studies.vaneless_bound [--seeds 3] [--json FILE]

Per vehicle (aerosonde, carbon_z) and sensor suite (vanes; a pitot without them, the
sensors a MAVLink link carries), flies the vehicle's default scenario and `--seeds`
variants of its fault-free one (turbulence and noise seeds from 601, background winds of
20-25 % of its airspeed: offline.fault_free_flights) through the offline chain with the
nodes' defaults for those sensors, and prints per fault:

- bound: the Cramer-Rao deviation of a constant fault over one window of the estimator
  (fault_bound.window_fault_bound, the wind errors' Gauss-Markov model, the suite's
  calibrated noise), median over the fault-free flights' windows after settle_s;
- the bound of the two wings' faults of one kind moving together (their mean) and apart
  (their half difference);
- the onset bound: on the default scenario, the RMS of the bound of an estimator told when
  each fault starts (onset_bound), to hold its RMS against;
- the default scenario's RMS error after settle_s, detection delay and false alarms;
- the fault-free flights' largest estimate after settle_s and their RMS (the estimator's
  steady-state error, to hold against the bound);
- the synthetic air data's flow-angle RMS against the simulator's (a pitot without vanes);
- and, per held-out seed, the default scenario flown in another turbulence and wind
  (offline.wind_variant: seeds from HELD_OUT_FIRST_SEED, background winds of 22 % of the
  airspeed, directions HELD_OUT_DIRECTIONS_DEG), on which no setting was tuned: RMS,
  delays, false alarms and flow-angle RMS.

Seeds other than the calibrations' (101-112, 201-212, 301-304) and the other studies'.
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
from uav_fault_estimator.chain.offline import (
    fault_free_flights,
    fly_and_estimate,
    scenario_estimator_settings,
    wind_variant,
)
from uav_fault_estimator.estimation.estimator_settings import EstimatorSettings
from uav_fault_estimator.estimation.estimator_step import SETTLE_S
from uav_fault_estimator.estimation.fault_bound import pair_bounds, window_fault_covariance
from uav_fault_estimator.estimation.noise_model import SUITES, load_noise_calibration, white_share
from uav_fault_estimator.estimation.prediction import residual_sampler
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.reporting.metrics import fault_metrics, flow_angle_rms_deg
from uav_sim.scenario import Scenario, load_scenario, vehicle_scenario_path
from uav_sim.simulation import Simulation

VEHICLES = ("aerosonde", "carbon_z")
SUITE_VANES = {"vanes": True, "pitot": False}  # the suites compared: air data with or without
FIRST_SEED = 601
WINDOW_STRIDE = 10  # samples between the windows whose bound is taken
# The two wings' faults of one kind: what moves them together (an angle of attack's error
# can) and what moves them apart (the rolling and yawing moments)
PAIRS = {"lift": ("right_wing_lift_loss", "left_wing_lift_loss"),
         "drag": ("right_wing_drag_increase", "left_wing_drag_increase")}
HELD_OUT_FIRST_SEED = 611
HELD_OUT_DIRECTIONS_DEG = (45.0, 165.0, 285.0)
HELD_OUT_WIND_SHARE = 0.22  # of the airspeed


def held_out_flights(scenario: Scenario) -> list[Scenario]:
    """The faulted scenario in other turbulence and winds (module docstring)."""
    speed_mps = HELD_OUT_WIND_SHARE * scenario.initial.airspeed_mps
    return [wind_variant(scenario, HELD_OUT_FIRST_SEED + i, direction, speed_mps)
            for i, direction in enumerate(HELD_OUT_DIRECTIONS_DEG)]


def with_vanes(scenario: Scenario, vanes: bool) -> Scenario:
    """The scenario with its pitot, and vanes or not."""
    return dataclasses.replace(scenario, sensors=dataclasses.replace(
        scenario.sensors, air_data=True, vanes=vanes))


def settled_samples(scenario: Scenario) -> list:
    """The flight's residual samples (prediction.ResidualSample) after SETTLE_S on which
    every row is valid, with the default residual settings for its sensors."""
    sampler = residual_sampler(ResidualSettings(vehicle=scenario.vehicle))
    simulation = Simulation(scenario)
    sample, samples = simulation.sample(), []
    while True:
        result = sampler.update(sample.time_s, sample.state, sample.controls,
                                sample.wind_filtered_ned_mps, sample.air_data)
        if result is not None and result.valid.all() and result.time_s >= SETTLE_S:
            samples.append(result)
        if simulation.finished:
            break
        sample = simulation.step()
    return samples


@dataclasses.dataclass(frozen=True)
class BoundModel:
    """What the bound of a flight's windows takes, read once per flight: the estimator's
    defaults for the scenario's sensors and each suite's calibrated white noise."""

    estimator: EstimatorSettings
    white_variances: dict[str, np.ndarray]

    @classmethod
    def of(cls, scenario: Scenario) -> BoundModel:
        noise = load_noise_calibration("", scenario.vehicle)
        return cls(scenario_estimator_settings(scenario), {
            suite: noise.variances[suite] / white_share(noise.correlations[suite])
            for suite in noise.variances})

    def covariance(self, window: list) -> np.ndarray:
        """window_fault_covariance of the window's samples, the noise of its newest
        sample's suite (p, p) [%^2]."""
        p = len(PAPER_FAULT_NAMES)
        wind_columns = slice(p, None) if self.estimator.estimate_wind_errors else slice(p, p)
        sensitivity = np.array([s.sensitivity for s in window])
        return window_fault_covariance(
            sensitivity[:, :, :p], sensitivity[:, :, wind_columns],
            self.white_variances[SUITES[window[-1].wind_source]],
            self.estimator.wind_error_sigma_mps, self.estimator.wind_error_coefficient)

    def bound(self, window: list) -> np.ndarray:
        """The deviation of each fault over the window (p,) [%]."""
        return np.sqrt(np.diag(self.covariance(window)))


def flight_bounds(scenario: Scenario) -> list[list[float]]:
    """Of every WINDOW_STRIDE-th estimator window after SETTLE_S of the fault-free flight,
    the bound of each fault (p), then of each PAIRS pair's mean and half difference [%]."""
    model, samples = BoundModel.of(scenario), settled_samples(scenario)
    horizon = model.estimator.horizon
    bounds = []
    for start in range(0, len(samples) - horizon + 1, WINDOW_STRIDE):
        covariance = model.covariance(samples[start:start + horizon])
        pairs = [pair_bounds(covariance, *(PAPER_FAULT_NAMES.index(name) for name in pair))
                 for pair in PAIRS.values()]
        bounds.append([*np.sqrt(np.diag(covariance)), *np.ravel(pairs)])
    return bounds


def onset_bound(scenario: Scenario) -> list[float]:
    """Per fault, the RMS over the faulted flight's samples after SETTLE_S of the bound of
    an estimator told when the fault starts: at each sample, BoundModel.bound over the
    estimator's window cut at the fault's start (the fault constant since; for a ramp,
    at its level, where one told the ramp's shape could do better) [%]. What the
    onsets cost any estimator, to hold the RMS of a faulted flight against."""
    model, samples = BoundModel.of(scenario), settled_samples(scenario)
    horizon = model.estimator.horizon
    starts_s = {fault.name: fault.start_s for fault in scenario.faults}
    squares = np.zeros(len(PAPER_FAULT_NAMES))
    for k, sample in enumerate(samples):
        window = samples[max(0, k + 1 - horizon):k + 1]
        whole = model.bound(window)
        for j, name in enumerate(PAPER_FAULT_NAMES):
            start_s = starts_s.get(name, np.inf)
            if window[0].time_s <= start_s < sample.time_s:  # started within the window
                since = [s for s in window if s.time_s > start_s]
                squares[j] += model.bound(since)[j] ** 2
            else:
                squares[j] += whole[j] ** 2
    return np.sqrt(squares / len(samples)).round(3).tolist()


def estimated(scenario: Scenario) -> dict:
    """The offline chain's figures of the flight: per fault its metrics and largest
    estimate after SETTLE_S, the false alarms and the synthetic flow angles' RMS [deg]
    (None with vanes)."""
    estimates, seeded = fly_and_estimate(scenario)
    faults, false_alarms = fault_metrics(estimates, seeded, SETTLE_S, THRESHOLD_PCT)
    settled = estimates.stamps_s >= SETTLE_S
    largest = estimates.values_pct[settled].max(axis=0)
    return {"faults": {name: {**faults[name], "largest_pct": float(largest[j])}
                       for j, name in enumerate(estimates.names)},
            "false_alarms": false_alarms,
            "flow_angle_rms_deg": flow_angle_rms_deg(estimates, SETTLE_S)}


def summarise(bounds: list, onsets: list, flights: list, seeds: int) -> dict:
    """Per vehicle and suite: per fault the bound, the default scenario's onset bound, RMS,
    delay and whether it false-alarmed, the fault-free flights' largest estimate and RMS;
    the default's flow-angle RMS; and per held-out seed its figures. bounds: per (vehicle,
    suite) its seeds fault-free flights'; onsets: per (vehicle, suite) its default
    scenario's; flights: per (vehicle, suite) its default scenario's, its fault-free
    flights', then its held-out flights'."""
    summary: dict = {}
    cells = [(vehicle, suite) for vehicle in VEHICLES for suite in SUITE_VANES]
    per_cell = 1 + seeds + len(HELD_OUT_DIRECTIONS_DEG)
    for k, (vehicle, suite) in enumerate(cells):
        windows = np.concatenate([np.array(b) for b in bounds[k * seeds:(k + 1) * seeds]])
        default, *others = flights[k * per_cell:(k + 1) * per_cell]
        free, held_out = others[:seeds], others[seeds:]
        pairs = windows[:, len(PAPER_FAULT_NAMES):]  # flight_bounds' pair columns
        summary.setdefault(vehicle, {})[suite] = {
            "faults": {
                name: {"bound_pct": round(float(np.median(windows[:, j])), 2),
                       "onset_bound_pct": onsets[k][j],
                       "rmse_pct": default["faults"][name]["rmse_pct"],
                       "delay_s": default["faults"][name]["detection_delay_s"],
                       "false_alarm": name in default["false_alarms"],
                       "fault_free_largest_pct": round(max(
                           f["faults"][name]["largest_pct"] for f in free), 2),
                       "fault_free_rmse_pct": round(max(
                           f["faults"][name]["rmse_pct"] for f in free), 2)}
                for j, name in enumerate(PAPER_FAULT_NAMES)},
            "pairs": {kind: {"mean_bound_pct": round(float(np.median(pairs[:, 2 * i])), 2),
                             "half_difference_bound_pct": round(float(np.median(
                                 pairs[:, 2 * i + 1])), 2)}
                      for i, kind in enumerate(PAIRS)},
            "flow_angle_rms_deg": default["flow_angle_rms_deg"],
            "held_out": [
                {"seed": HELD_OUT_FIRST_SEED + i,
                 "rmse_pct": [f["faults"][name]["rmse_pct"] for name in PAPER_FAULT_NAMES],
                 "delay_s": [f["faults"][name]["detection_delay_s"]
                             for name in PAPER_FAULT_NAMES],
                 "false_alarms": f["false_alarms"],
                 "flow_angle_rms_deg": f["flow_angle_rms_deg"]}
                for i, f in enumerate(held_out)]}
    return summary


# The table's per-fault columns before and after the false alarms, and their formats
_COLUMNS = (("bound_pct", ".2f"), ("onset_bound_pct", ".2f"), ("rmse_pct", ".2f"),
            ("delay_s", "g"),
            ("fault_free_largest_pct", ".2f"), ("fault_free_rmse_pct", ".2f"))


def _per_fault(faults: dict, key: str, form: str) -> str:
    """One figure of every fault, "-" where there is none, joined by " / "."""
    return " / ".join("-" if v[key] is None else format(v[key], form) for v in faults.values())


def print_table(summary: dict) -> None:
    print("| vehicle | sensors | bound [%] | onset bound [%] | rmse [%] | delay [s] | "
          "false alarms | fault-free largest [%] | fault-free rmse [%] | flow angles [deg] |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for vehicle, suites in summary.items():
        for suite, cell in suites.items():
            faults = cell["faults"]
            alarms = ", ".join(n for n, v in faults.items() if v["false_alarm"]) or "none"
            cells = [_per_fault(faults, key, form) for key, form in _COLUMNS]
            cells.insert(4, alarms)
            print(f"| {vehicle} | {suite} | " + " | ".join(cells)
                  + f" | {cell['flow_angle_rms_deg'] or '-'} |")
    print("\nThe two wings' faults of one kind: bound of their mean / of their half difference")
    for vehicle, suites in summary.items():
        for suite, cell in suites.items():
            print(f"| {vehicle} | {suite} | " + " | ".join(
                f"{kind} {v['mean_bound_pct']:.2f} / {v['half_difference_bound_pct']:.2f}"
                for kind, v in cell["pairs"].items()) + " |")
    print("\nHeld-out seeds of the default scenario")
    print("| vehicle | sensors | seed | rmse [%] | delay [s] | false alarms | flow angles [deg] |")
    print("|---|---|---|---|---|---|---|")
    for vehicle, suites in summary.items():
        for suite, cell in suites.items():
            for flight in cell["held_out"]:
                print(f"| {vehicle} | {suite} | {flight['seed']} | {flight['rmse_pct']} | "
                      f"{flight['delay_s']} | {', '.join(flight['false_alarms']) or 'none'} | "
                      f"{flight['flow_angle_rms_deg'] or '-'} |")


@exit_on_failed_tasks
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--json", type=Path, help="also write the summary here")
    add_campaign_arguments(parser)
    arguments = parser.parse_args()
    started = time.monotonic()
    free, defaults, flown = [], [], []
    for vehicle in VEHICLES:
        quiet = fault_free_flights(arguments.seeds, FIRST_SEED, vehicle=vehicle)
        faulted = load_scenario(vehicle_scenario_path(vehicle, "default"))
        for vanes in SUITE_VANES.values():
            free += [with_vanes(s, vanes) for s in quiet]
            defaults.append(with_vanes(faulted, vanes))
            flown += [with_vanes(s, vanes)
                      for s in (faulted, *quiet, *held_out_flights(faulted))]
    with Campaign(campaign_options(arguments)) as campaign:
        bounds = campaign.results(flight_bounds, free, "bound flights")
        onsets = campaign.results(onset_bound, defaults, "onset bounds")
        flights = campaign.results(estimated, flown, "estimated flights")
    summary = summarise(bounds, onsets, flights, arguments.seeds)
    print_table(summary)
    print(f"\n{len(free) + len(flown)} flights in {time.monotonic() - started:.0f} s")
    if arguments.json:
        arguments.json.write_text(json.dumps(
            {"seeds": arguments.seeds, "first_seed": FIRST_SEED,
             "held_out_wind_share": HELD_OUT_WIND_SHARE, "settle_s": SETTLE_S,
             "threshold_pct": THRESHOLD_PCT, "summary": summary}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
