#!/usr/bin/env python3
"""Write docs/results.md, the measured figures, from the JSON files the benchmarks, the
studies and the demo write into docs/.

    python tools/results_page.py            # (re)write docs/results.md
    python tools/results_page.py --check    # exit 1 when docs/results.md is out of date

One section per source, each saying which command regenerates its JSON; a source whose
JSON is missing says so and how to make it. The page is a pure function of the JSON files
(no dates, no machine names), so --check tells whether someone changed a JSON file without
regenerating the page, or edited the page by hand. No ROS here.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from uav_fault_estimator.flight_logs.evaluation import within_counts

REPO_ROOT = Path(__file__).resolve().parent.parent
DOCS = REPO_ROOT / "docs"
PAGE = "results.md"
# metrics.json files of demo runs, copied into docs/: demo_<scenario>.json
DEMO_PATTERN = "demo_*.json"

Renderer = Callable[[Any], list[str]]


def number(value: Any) -> str:
    """A figure as the tables show it: 4 significant digits, '-' for none."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if value == 0.0 or not math.isfinite(value):
            return f"{value:g}"
        if 1e-3 <= abs(value) < 1e5:
            return f"{value:.4g}"
        return f"{value:.2e}"
    if isinstance(value, list | tuple):
        return ", ".join(number(item) for item in value) or "-"
    return str(value)


def table(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> list[str]:
    """A markdown table; cells that are not strings are formatted by number(), and a "|"
    in a cell is escaped."""
    def line(cells: Iterable[str]) -> str:
        return "| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |"

    lines = [line(header), "|" + "---|" * len(header)]
    for row in rows:
        lines.append(line(cell if isinstance(cell, str) else number(cell) for cell in row))
    return [*lines, ""]


def key_values(data: Mapping[str, Any], keys: Iterable[str] | None = None) -> list[str]:
    """A two-column table of the mapping's scalar entries (or of `keys`, in that order)."""
    names = list(keys) if keys is not None else [
        key for key, value in data.items() if not isinstance(value, dict | list)]
    return table(("figure", "value"), ((f"`{key}`", data.get(key)) for key in names))


# --- the estimator benchmark (benchmarks/bench_mhe.py) ---------------------------------


def _solvers(solvers: Mapping[str, Mapping[str, Any]]) -> list[str]:
    return table(("solver", "tolerance", "median [ms]", "p99 [ms]", "deviation"), (
        (name, "exact" if entry.get("eps") is None else number(entry["eps"]),
         entry.get("median_ms"), entry.get("p99_ms"), entry.get("max_deviation"))
        for name, entry in solvers.items()))


def _against(data: Mapping[str, Any], what: str, label: str) -> list[str]:
    """Median and p99 per horizon or fault count, ProxSuite and the active set."""
    median, p99 = data.get(f"{what}_median_ms", {}), data.get(f"{what}_p99_ms", {})
    active_median = data.get(f"active_set_{what}_median_ms", {})
    active_p99 = data.get(f"active_set_{what}_p99_ms", {})
    return table((label, "ProxSuite median [ms]", "ProxSuite p99 [ms]",
                  "active set median [ms]", "active set p99 [ms]"), (
        (key, median.get(key), p99.get(key), active_median.get(key), active_p99.get(key))
        for key in sorted(median, key=float)))


def bench_mhe(data: Mapping[str, Any]) -> list[str]:
    lines = [f"The project's row: `{data.get('estimator')}`. Deviation: the largest "
             "|x - x_ref| / max(1, |x_ref|) against the reference (Clarabel at 1e-12, "
             "polished); times per update, the fastest of the passes over the same sequence.",
             "", "### Solvers, four faults", ""]
    lines += _solvers(data.get("solvers", {}))
    if data.get("solvers_with_wind_errors"):
        lines += ["### Solvers, without vanes (four faults and three wind errors)", ""]
        lines += _solvers(data["solvers_with_wind_errors"])
    lines += ["### Against the horizon", "", "N residual samples in the window, p = 4, the "
              "flown sequence.", ""]
    lines += _against(data, "horizon", "N")
    lines += ["### Against the fault count", "", "p estimated faults, N = 50, synthetic "
              "sequences.", ""]
    lines += _against(data, "fault_count", "p")
    if data.get("anatomy"):
        keys = ("update_ms", "proxsuite_setup_ms", "proxsuite_solve_ms", "iterations",
                "penalty_updates")
        lines += ["### Where the update goes", "", "ProxSuite's own timings; `median` over "
                  "the updates, `slowest_1pct_mean` the mean of the slowest 1 %.", ""]
        lines += table(("N", "updates", *keys), (
            (entry.get("horizon"), group, *(entry.get(group, {}).get(key) for key in keys))
            for entry in data["anatomy"] for group in ("median", "slowest_1pct_mean")))
    if data.get("active_set_bound"):
        lines += ["### Reduced to the active set", "", "Each window's QP with its known "
                  "active set, solved by ProxSuite's dense backend.", ""]
        lines += key_values(data["active_set_bound"])
    if data.get("proxsuite_floor"):
        lines += ["### ProxSuite from the exact solution", "", "ProxSuite handed each "
                  "window's exact primal and dual solution: the floor of any warm start.", ""]
        lines += key_values(data["proxsuite_floor"])
    return lines


# --- detectability (studies/detectability.py) -------------------------------------------


def detectability(data: Mapping[str, Any]) -> list[str]:
    lines = [f"{data.get('seeds')} flights per suite and turbulence (seeds from "
             f"{data.get('first_seed')}); errors after {number(data.get('settle_s'))} s; "
             f"threshold {number(data.get('threshold_pct'))} %. Fault-free largest: the "
             "largest fault-free estimate over the flights (the smallest threshold free of "
             f"false alarms on them); after start: the same after "
             f"{number(data.get('start_s'))} s. RMS error and worst delay: the default "
             "faults.", ""]
    keys = ("fault_free_largest_pct", "fault_free_largest_after_start_pct", "rmse_mean_pct",
            "rmse_worst_pct", "delay_worst_s")
    rows = [(suite, turbulence, fault, *(figures.get(key) for key in keys))
            for suite, levels in data.get("summary", {}).items()
            for turbulence, faults in levels.items()
            for fault, figures in faults.items()]
    return lines + table(("suite", "turbulence", "fault", "fault-free largest [%]",
                          "after start [%]", "RMS mean [%]", "RMS worst [%]",
                          "worst delay [s]"), rows)


# --- without vanes (studies/vaneless_bound.py) ----------------------------------------------


def _default_flight(cell: Mapping[str, Any]) -> dict:
    """The default scenario's (seed 7) figures of a vaneless_bound cell, as a held-out
    flight's."""
    faults = cell.get("faults", {})
    return {"seed": 7, "rmse_pct": [f.get("rmse_pct") for f in faults.values()],
            "delay_s": [f.get("delay_s") for f in faults.values()],
            "false_alarms": [name for name, f in faults.items() if f.get("false_alarm")],
            "flow_angle_rms_deg": cell.get("flow_angle_rms_deg")}


def vaneless_bound(data: Mapping[str, Any]) -> list[str]:
    lines = [f"The default scenario and {data.get('seeds')} fault-free flights per vehicle and "
             f"sensors (seeds from {data.get('first_seed')}); after "
             f"{number(data.get('settle_s'))} s; threshold {number(data.get('threshold_pct'))} "
             "%. Bound: the Cramer-Rao deviation of a constant fault over one estimator "
             "window (median over the fault-free flights' windows); onset bound: on the "
             "default scenario, the RMS of that bound for an estimator told when each fault "
             "starts (its window cut there), what the onsets cost any estimator, to hold the "
             "RMS against; RMS, delay, false alarm: "
             "the default scenario; fault-free: the largest estimate and the worst RMS over "
             "the fault-free flights (the steady state, to hold against the bound).", ""]
    keys = ("bound_pct", "onset_bound_pct", "rmse_pct", "delay_s", "false_alarm",
            "fault_free_largest_pct", "fault_free_rmse_pct")
    summary = data.get("summary", {})
    rows = [(vehicle, suite, fault, *(figures.get(key) for key in keys))
            for vehicle, suites in summary.items()
            for suite, cell in suites.items()
            for fault, figures in cell.get("faults", {}).items()]
    lines += table(("vehicle", "sensors", "fault", "bound [%]", "onset bound [%]", "RMS [%]",
                    "delay [s]",
                    "false alarm", "fault-free largest [%]", "fault-free RMS [%]"), rows)
    lines += ["The two wings' faults of one kind: the bound (median over the fault-free "
              "flights' windows, as above) of their mean, which a flow angle's error "
              "moves as well, and of their half difference, which the rolling and yawing "
              "moments tell.", ""]
    lines += table(("vehicle", "sensors", "lift: mean [%]", "lift: half difference [%]",
                    "drag: mean [%]", "drag: half difference [%]"), (
        (vehicle, suite, *(cell.get("pairs", {}).get(kind, {}).get(key)
                           for kind in ("lift", "drag")
                           for key in ("mean_bound_pct", "half_difference_bound_pct")))
        for vehicle, suites in summary.items() for suite, cell in suites.items()))
    lines += ["The default scenario on held-out seeds (turbulence, noise and a background wind "
              f"of {number(100 * (data.get('held_out_wind_share') or 0))} % of the airspeed "
              "from another direction; no setting was tuned on them), per fault in the order "
              "of the table above; flow angles: the synthetic angle of attack's and "
              "sideslip's RMS against the simulator's [deg]. Seed 7: the default scenario "
              "itself.", ""]
    rows = [(vehicle, suite, flight.get("seed"), flight.get("rmse_pct"), flight.get("delay_s"),
             ", ".join(flight.get("false_alarms") or []) or "none",
             flight.get("flow_angle_rms_deg"))
            for vehicle, suites in summary.items()
            for suite, cell in suites.items()
            for flight in [_default_flight(cell), *cell.get("held_out", [])]]
    return lines + table(("vehicle", "sensors", "seed", "RMS [%]", "delay [s]",
                          "false alarms", "flow angles [deg]"), rows)


# --- the soak (benchmarks/soak.py) --------------------------------------------------------


def soak(data: Mapping[str, Any]) -> list[str]:
    lines = key_values(data, ("duration_s", "seed", "events", "estimates_expected",
                              "estimates_clean", "estimates_dirty", "residuals_injected",
                              "settle_s", "stamps_outside", "stamps_inside", "wall_s"))
    lost = ("estimates_lost_clean", "estimates_lost_dirty", "estimates_unexpected")
    lines += table(("stamps", "count"), ((f"`{key}`", len(data.get(key) or [])) for key in lost))
    lines += table(("largest difference of the disturbed estimates from the clean", "[%]",
                    "at [s]"), (
        (label, *(data.get(key) or (None, None)))
        for label, key in (("outside the disturbed windows", "largest_error_outside_pct_at_s"),
                           ("inside them", "largest_error_inside_pct_at_s"))))
    times = data.get("event_times_s", {})
    lines += table(("event", "count", "at [s]"), (
        (kind, count, times.get(kind, [])) for kind, count in data.get("event_kinds", {}).items()))
    start, end = data.get("memory_start_mb", {}), data.get("memory_end_mb", {})
    return lines + table(("disturbed node", "memory at start [MB]", "memory at end [MB]"),
                         ((node, start.get(node), end.get(node)) for node in start))


# --- the airspeed schedule (studies/airspeed_schedule.py) -------------------------------

CALIBRATIONS = ("one_airspeed", "unscheduled", "scheduled")
TESTS = ("glrt_roll", "glrt_pitch", "glrt_yaw", "parameters", "combined")


def airspeed_schedule(data: Mapping[str, Any]) -> list[str]:
    lines = [f"False-alarm rate per sample against the designed "
             f"{number(data.get('designed_false_alarm_probability'))}; calibrations: "
             "`one_airspeed` (25 m/s alone), `unscheduled` and `scheduled` (from "
             f"{data.get('calibration_flights_per_airspeed')} flights at each of "
             f"{number(data.get('calibration_airspeeds_mps'))} m/s); "
             f"{data.get('test_flights_per_airspeed')} fault-free test flights per airspeed.",
             ""]
    present = [name for name in CALIBRATIONS if name in data]
    airspeeds = list(data[present[0]]["false_alarm_rates"]) if present else []
    lines += table(("airspeed [m/s]", "calibration", *TESTS), (
        (airspeed, name, *(data[name]["false_alarm_rates"][airspeed].get(test)
                           for test in TESTS))
        for airspeed in airspeeds for name in present))
    delays = sorted({key for name in present for key in data[name]["aileron_loss_delay_s"]},
                    key=float)
    return lines + table(
        ("calibration", *(f"aileron loss found after [s] at {key} m/s" for key in delays),
         "roll gain spread"),
        ((name, *(data[name]["aileron_loss_delay_s"].get(key) for key in delays),
          data[name].get("roll_gain_std")) for name in present))


# --- the guidance benchmark (benchmarks/bench_guidance.py) --------------------------------

GUIDANCE_COLUMNS = ("wind_pct", "method", "cross_track_rms_m", "cross_track_largest_m",
                    "corners", "solve_ms_median", "solve_ms_p99", "largest_yaw_rate_over_limit",
                    "fallbacks")


def guidance(data: Mapping[str, Any]) -> list[str]:
    lines = [f"Scenario `{data.get('scenario')}` (seed {data.get('seed')}, "
             f"{number(data.get('duration_s'))} s), cross-track error after the first "
             f"{number(data.get('settle_s'))} s; wind in % of the airspeed, with its "
             "turbulence; solve times are ProxSuite's.", ""]
    lines += table(GUIDANCE_COLUMNS, ([flight.get(column) for column in GUIDANCE_COLUMNS]
                                      for flight in data["flights"]))
    settle_s, threshold_pct = data.get("estimator_settle_s"), data.get("threshold_pct")
    lines += [f"The estimator on each method's fault-free flights in the paper's wind, seeds "
              f"it was not tuned on: the largest estimate after {number(settle_s)} s per "
              f"flight, against the {number(threshold_pct)} % threshold.", ""]
    return lines + table(
        ("method", "largest estimate per flight [%]", "mean [%]", "flights reaching it"),
        ((margin["method"], " / ".join(number(v) for v in margin["largest_estimate_pct"]),
          margin["mean_largest_pct"], margin["reaching_threshold"])
         for margin in data.get("estimator", [])))


# --- the campaign layer (benchmarks/bench_campaigns.py) -----------------------------------

def campaigns(data: Mapping[str, Any]) -> list[str]:
    flown, cost = data["flights"], data["per_task"]
    lines = [f"{flown['flights']} detectability flights (300 s each, through the offline "
             f"chain), results equal: {number(flown.get('equal_results'))}.", ""]
    lines += table(("in one process [s]", "on 2 local workers [s]", "of which cluster start-up "
                    "[s]", "times faster", "s per flight", "result [B]", "worker memory [MB]"),
                   [(flown["serial_s"], flown["parallel_s"], flown["cluster_startup_s"],
                     flown["speedup"], flown["seconds_per_flight"], flown["result_bytes_mean"],
                     flown["worker_memory_mb_largest"])])
    cluster = data["cluster"]
    lines += [f"Per task, warm, over {cost['tasks']} tasks that return their input: Dask "
              f"{number(cost['dask_ms_per_task'])} ms, a process pool "
              f"{number(cost['process_pool_ms_per_task'])} ms. Through a scheduler's address "
              f"(2 local workers on 127.0.0.1, as `--cluster` reaches one): plain TCP "
              f"{number(cluster['tcp_ms_per_task'])} ms, TLS "
              f"{number(cluster['tls_ms_per_task'])} ms; {cluster['tls_flights']} of the "
              f"flights over TLS equal to the serial run bit for bit: "
              f"{number(cluster['tls_flights_equal_serial'])}.", "",
              "A 10,000-flight detectability map, scaled from the flights above:", ""]
    return lines + table(("flights (tasks)", "CPU hours", "workers", "wall hours",
                          "memory per worker [MB]", "results [MB]"),
                         ((plan["tasks"], plan["cpu_hours"], plan["workers"],
                           plan["wall_hours"], plan["worker_memory_mb"], plan["results_mb"])
                          for plan in data["plans"]))


# --- the onboard graph behind the MAVLink link (benchmarks/bench_onboard.py) -------------

def onboard(data: Mapping[str, Any]) -> list[str]:
    nodes = data["nodes"]
    lines = [f"Scenario `{Path(data['scenario']).name}`, {number(data['duration_s'])} s of "
             f"flight through the link as {data['stack']}; CPU while the aircraft flies "
             "(start-up and shutdown left out).", ""]
    lines += table(("node", "CPU-s per flight s", "peak memory [MB]", "runs on"),
                   ((node, figures["cpu_s_per_flight_s"], figures["peak_mb"],
                     "the aircraft (played)" if node in data["on_the_aircraft"]
                     else "the companion computer")
                    for node, figures in nodes.items()))
    share_pct = number(100 * data["bridge_cpu_share_of_residual_node"])
    return [*lines, f"mavlink_node's CPU is {share_pct} % of residual_node's.", ""]


# --- the detector on ALFA's real flights (scripts/alfa_benchmark.py) ----------------------

ALFA_COLUMNS = ("flight", "failure", "outcome", "delay_s", "first_alarm_channel",
                "alarms_before_onset", "flown_after_onset_s")


ALFA_SUMMARY = (("tp", "tp"), ("fp", "fp"), ("fn", "fn"), ("tn", "tn"),
                ("precision", "precision"), ("recall", "recall"), ("accuracy", "accuracy"),
                ("mean delay [s]", "mean_delay_s"), ("largest delay [s]", "max_delay_s"),
                ("first alarm on the failed part", "right_channel"))


def alfa_counts(name: str, summary: Mapping[str, Any]) -> list[list[Any]]:
    """Rows of one detector's summary: within the limit (ALFA's evaluator) and at any delay."""
    within = within_counts(summary, summary["detection_limit_s"])
    return [[name, f"within {number(summary['detection_limit_s'])} s",
             *(within[field] for _, field in ALFA_SUMMARY)],
            [name, "at any delay", *(summary[field] for _, field in ALFA_SUMMARY)]]


def alfa_kinds(name: str, summary: Mapping[str, Any]) -> list[list[Any]]:
    """Rows per failure kind of one detector's summary, Keipour et al.'s table."""
    rows = []
    for kind, every in summary["by_kind"].items():
        within = within_counts(every, summary["detection_limit_s"])
        rows.append([name, kind, every["flights"], every["tp"], every["mean_delay_s"],
                     every["max_delay_s"], within["tp"], within["mean_delay_s"],
                     within["max_delay_s"], every["fp"]])
    return rows


def alfa_benchmark(data: Mapping[str, Any]) -> list[str]:
    summaries = {"project": data["summary"],
                 **{name: peer["summary"] for name, peer in data.get("peers", {}).items()}}
    limit = f"within {number(data['summary']['detection_limit_s'])} s"
    lines = [f"{data.get('mode')}, generators {', '.join(data.get('generators', []))}, "
             f"schedule {data.get('schedule')}, designed P_FA "
             f"{number(data.get('false_alarm_probability'))} per sample and test; counted per "
             f"flight (docs/flight_logs.md), {limit} of the onset as ALFA's evaluator counts "
             "and at any delay; the peers on the same flights, in the same folds.", ""]
    lines += table(("detector", "counted", *(title for title, _ in ALFA_SUMMARY)),
                   (row for name, summary in summaries.items()
                    for row in alfa_counts(name, summary)))
    lines += table(("detector", "failure kind", "flights", "found", "mean delay [s]",
                    "largest delay [s]", f"found {limit}", "mean delay [s]",
                    "largest delay [s]", "fp"),
                   (row for name, summary in summaries.items()
                    for row in alfa_kinds(name, summary)))
    return lines + table(ALFA_COLUMNS, ([flight.get(column) for column in ALFA_COLUMNS]
                                        for flight in data["flights"]))


# --- the model error study (studies/model_error.py) --------------------------------------

RUN_FIGURES = (("fault-free largest [%]", "fault_free_largest_pct"),
               ("default finals [%]", "default_final_pct"), ("default RMS [%]", "default_rmse_pct"),
               ("default delays [s]", "default_delay_s"))


def model_error(data: Mapping[str, Any]) -> list[str]:
    """Per flown aircraft, the test flights without and with its calibration, and what the
    calibration found."""
    lines = ["Faults in the order right wing lift loss, right wing drag increase, left wing "
             "lift loss, left wing drag increase (default flight seeded 10 / 20 / 15 / 25 %).",
             ""]
    lines += table(("flown aircraft", "model", *(label for label, _ in RUN_FIGURES),
                    "false alarms"), (
        (name, "calibrated" if label == "with" else "shipped",
         *(number(list(result[label][key].values())).replace(", ", " / ")
           for _, key in RUN_FIGURES),
         ", ".join(sorted(set(result[label]["fault_free_false_alarms"]
                              + result[label]["default_false_alarms"]))) or "none")
        for name, result in data.items() for label in ("without", "with")))
    return lines + table(("flown aircraft", "calibration wall [s]",
                          "found (value ± posterior deviation)"), (
        (name, result.get("calibration_wall_s"), "; ".join(
            f"{key} {number(value)} ± {number(deviation)}"
            for key, (value, deviation) in result.get("calibrated", {}).items()))
        for name, result in data.items()))


# --- the random aircraft study (studies/random_aircraft.py) ------------------------------


def random_aircraft(data: Mapping[str, Any]) -> list[str]:
    """The totals, then per aircraft the calibration's fit and check, the test flights'
    figures and the targets they miss."""
    totals, targets = data["summary"], data["targets"]
    measured = data.get("measured_mass_properties")
    on_the_ground = ("the model given each aircraft's CG and inertia as measured on the "
                     f"ground (within {', '.join(f'{k} {number(v)}' for k, v in measured.items())})"
                     if measured else "nothing measured on the ground")
    condition = data.get("calibration_condition", "turbulence, sensor noise")
    plan = data.get("calibration_plan")
    flights = (f"the calibration plan's flights ({', '.join(plan)})" if plan
               else "three ordinary fault-free flights at 22, 25 and 28 m/s")
    lines = [f"{data['count']} aircraft drawn about the {data.get('vehicle', 'aerosonde')} "
             f"with seed {data['seed']} (draw half-widths "
             f"{', '.join(f'{k} {number(v)}' for k, v in data['draw'].items())}) and the "
             f"model's own; calibrated from {flights} in {condition}; parameters "
             f"{', '.join(data['parameters'])}; {on_the_ground}. Targets: fault-free "
             f"largest below {number(targets['fault_free_below_pct'])} %, RMS at most "
             f"{number(100 * targets['rmse_share'])} % and final within "
             f"{number(100 * targets['final_share'])} % of each magnitude, found within "
             f"{number(targets['detected_within_s'])} s, no false alarm. Faults in the order "
             "right wing lift loss, right wing drag increase, left wing lift loss, left wing "
             "drag increase (10 / 20 / 15 / 25 %).", ""]
    lines += key_values({
        "drawn aircraft meeting the targets": f"{totals['meet_targets']} of {totals['aircraft']}",
        "not meeting them, flagged by the check": totals["failing_flagged"],
        "not meeting them, not flagged": ", ".join(totals["failing_not_flagged"]) or "none",
        "meeting them, flagged": totals["meeting_flagged"],
        "wall time [s]": data.get("wall_time_s")})
    return lines + table(
        ("aircraft", "weighted residual per row", "check warnings", *(label for label, _ in
                                                                      RUN_FIGURES),
         "false alarms", "targets missed"),
        ((row["name"], row["weighted_residual_per_row"], len(row["check"]),
          *(number(list(row[key].values())).replace(", ", " / ") for _, key in RUN_FIGURES),
          ", ".join(sorted(set(row["false_alarms"]))) or "none",
          "; ".join(row["missed"]) or "none") for row in data["aircraft"]))


# --- the calibration's bias on the model's own aircraft (studies/calibration_bias.py) ----


def calibration_bias(data: Mapping[str, Any]) -> list[str]:
    """Per parameter and condition the mean value over the seed sets, [smallest, largest],
    and the mean posterior deviation."""
    conditions = list(data["conditions"])
    excitation = data.get("excitation")
    flown = ("with these setpoint changes (start [s], airspeed and altitude change [m/s, m]): "
             + "; ".join(f"{number(t)}: {number(v)}, {number(h)}" for t, v, h in excitation)
             if excitation else "level, at one airspeed each")
    lines = [f"#### Calibration flights {'excited' if excitation else 'level'}", "",
             f"The calibration flights flown {flown}. "
             f"The model's own aircraft calibrated from its three calibration flights, "
             f"{data['seed_sets']} seed sets per condition; a value is the parameter's "
             "mean over the seed sets [smallest, largest] ± its mean posterior deviation, "
             "in the parameter's unit (0 is the model). Wall time "
             f"{number(data.get('wall_time_s'))} s.", ""]
    summary = data["summary"]
    return lines + table(("parameter", *conditions), (
        (name, *(f"{number(entry['mean'])} [{number(entry['min'])}, {number(entry['max'])}]"
                 f" ± {number(entry['posterior_std'])}"
                 for entry in (summary[condition][name] for condition in conditions)))
        for name in data["parameters"]))


# --- demo runs (metrics.json of scripts/demo.sh) ----------------------------------------


def failure_kinds(data: Mapping[str, Any]) -> list[str]:
    """Each failure kind and model fault seeded in simulation: per kind, the flights the
    twin bound calls detectable within the limit and of them those the sliding bound finds,
    those the detector finds within it (of them), found at all, named right, the detector's
    and the bound's median delays, the largest delay and the early alarms; the fault-free
    flights with an alarm."""
    magnitudes = ", ".join(f"{name} {number(pct)} %" for name, pct in
                           data["magnitudes_pct"].items())
    lines = [f"Vehicle `{data['vehicle']}`, {data['flights_per_kind']} flights per kind "
             f"(seeds from {data['first_seed']}), generators {', '.join(data['generators'])}; "
             f"model faults as steps and as ramps over {number(data['ramp_s'])} s ({magnitudes}),"
             f" delays from the onset (a ramp's: from reaching 2 %), found within "
             f"{number(data['within_s'])} s:", ""]
    keys = ("detectable_within_5_s", "sliding_bound_found", "found_within_5_s",
            "detectable_found_within_5_s", "found", "named_right", "median_delay_s",
            "median_bound_delay_s", "largest_delay_s", "false_alarm_flights")
    lines += table(("kind", "flights", *keys), (
        (kind, entry["flights"], *(entry.get(key) for key in keys))
        for kind, entry in data["kinds"].items()))
    return lines + key_values(data, ("wall_s",))


def alfa_model_fit(data: Mapping[str, Any]) -> list[str]:
    """A vehicle's model on real no-failure flights: per flight, the residual RMS per channel
    of the shipped model and of the one calibrated on the other days, beside the noise the
    simulator assumes; the parameters each calibration found."""
    channels = data["channels"]
    lines = [f"Vehicle `{data['vehicle']}`; residual RMS per channel ({', '.join(channels)}; "
             "m/s², rad/s²). Fitted: " + ", ".join(data["parameters_fitted"]) + ".", ""]
    rows = [["assumed noise", "-", *data["assumed_noise_rms"]]]
    for name, flight in data["flights"].items():
        rows.append([f"{name} shipped", flight["duration_s"], *flight["shipped_rms"]])
        rows.append([f"{name} calibrated without {flight['day_left_out']}",
                     flight["duration_s"], *flight["calibrated_rms"]])
    lines += table(("flight", "s", *channels), rows)
    found = {flight["day_left_out"]: flight["parameters"] for flight in data["flights"].values()}
    names = data["parameters_fitted"]
    lines += table(("day left out", *names), ((day, *(values[n] for n in names))
                                              for day, values in found.items()))
    return lines + key_values(data, ("wall_s",))


def demo_run(metrics: Mapping[str, Any]) -> list[str]:
    """One run's metrics.json: the demo's table, with its solver and pipeline figures."""
    lines = [f"#### Scenario `{metrics.get('scenario')}`", "",
             f"{number(metrics.get('duration_s'))} s, settle {number(metrics.get('settle_s'))}"
             f" s, threshold {number(metrics.get('detection_threshold_pct'))} %; estimator "
             f"false alarms: {', '.join(metrics.get('false_alarms') or []) or 'none'}; guidance "
             f"{(metrics.get('aircraft') or {}).get('guidance') or '-'}.", ""]
    keys = ("seeded", "seeded_final_pct", "estimate_final_pct", "rmse_pct",
            "max_abs_error_pct", "detection_delay_s")
    lines += table(("fault", *keys), ((name, *(fault.get(key) for key in keys))
                                      for name, fault in metrics.get("faults", {}).items()))
    return lines + key_values(flattened({"solver": metrics.get("solver", {}),
                                         "pipeline": metrics.get("pipeline", {})}))


def flattened(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested mappings as one, their keys joined by dots (`pipeline.wall_s`)."""
    flat: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, Mapping):
            flat |= flattened(value, f"{prefix}{key}.")
        else:
            flat[f"{prefix}{key}"] = value
    return flat


@dataclass(frozen=True)
class Section:
    """One section of the page: its heading, the JSON file(s) it renders (a name in docs/,
    or a glob), the command that regenerates them, and how to render one file."""

    title: str
    source: str
    command: str
    render: Renderer
    text: str


SECTIONS = (
    Section("Demo runs", DEMO_PATTERN,
            "./scripts/demo.sh SCENARIO.yaml --out runs/NAME && "
            "cp runs/NAME/metrics.json docs/demo_NAME.json", demo_run,
            "metrics.json of demo runs through the ROS graph (docs/design.md defines the "
            "figures): one subsection per file docs/demo_NAME.json."),
    Section("Onboard graph", "bench_onboard.json",
            "python -m benchmarks.bench_onboard --duration 120 --json docs/bench_onboard.json",
            onboard, "The onboard graph behind an autopilot's MAVLink link (docs/onboard.md): "
            "each node's CPU per second of flight and its peak memory."),
    Section("Estimator benchmark", "bench_mhe.json",
            "python -m benchmarks.bench_mhe --updates 200 --json docs/bench_mhe.json", bench_mhe,
            "The estimator's update against other QP solvers on the same windows "
            "(docs/performance.md)."),
    Section("Detectability", "detectability.json",
            "python -m studies.detectability --json docs/detectability.json", detectability,
            "Per sensor suite and turbulence, the default and fault_free scenarios flown "
            "through the offline chain with the node defaults (docs/estimator.md)."),
    Section("Without vanes", "vaneless_bound.json",
            "python -m studies.vaneless_bound --json docs/vaneless_bound.json", vaneless_bound,
            "A pitot without vanes against vanes, each vehicle's default and fault-free "
            "flights through the offline chain with the node defaults for those sensors, "
            "beside the bound of what any estimator could do (docs/onboard.md)."),
    Section("Soak", "soak.json", "python -m benchmarks.soak --json docs/soak.json", soak,
            "A long flight replayed into a clean and a disturbed copy of the nodes, the "
            "disturbed one given bad messages (docs/performance.md)."),
    Section("Model error", "model_calibration.json",
            "python -m studies.model_error --json docs/model_calibration.json", model_error,
            "Flown aircraft that differ from the model, each flown through the ROS graph "
            "without and with a calibration from three fault-free flights of it at 22, 25 and "
            "28 m/s (docs/model_calibration.md)."),
    Section("Random aircraft", "random_aircraft*.json",
            "python -m studies.random_aircraft --json docs/random_aircraft.json && "
            "python -m studies.random_aircraft --count 12 --calibration-condition "
            "'calm air, ideal sensors' --json docs/random_aircraft_ideal.json && "
            "python -m studies.random_aircraft --count 12 --calibration-condition "
            "'calm air, ideal sensors' --parameters coefficients,mass_scale,thrust_scale,"
            "cg_y_cm,airspeed_scale,angle_of_attack_deg,sideslip_deg --json "
            "docs/random_aircraft_ideal_all.json && python -m studies.random_aircraft "
            "--count 12 --plan --json docs/random_aircraft_plan.json && python -m "
            "studies.random_aircraft --seed 2 --plan --json "
            "docs/random_aircraft_plan_fresh.json && python -m studies.random_aircraft "
            "--seed 2 --json docs/random_aircraft_fresh.json",
            random_aircraft,
            "Aircraft drawn at random about the model, each calibrated from three fault-free "
            "flights of it and flown through the offline chain with its calibration; the "
            "calibration's own check beside whether the targets are met. The _ideal files: "
            "the same aircraft calibrated from the same flights flown in calm air with ideal "
            "sensors (the best these flights can give), with the default parameters and with "
            "all 37 (every aerodynamic coefficient); the _plan file: calibrated from the "
            "vehicle's calibration plan instead; the _fresh files: 40 aircraft of a seed "
            "nothing was chosen on, from the plan and from the ordinary flights "
            "(docs/model_calibration.md)."),
    Section("Calibration bias", "calibration_bias*.json",
            "python -m studies.calibration_bias --json docs/calibration_bias.json && "
            "python -m studies.calibration_bias --excite --json "
            "docs/calibration_bias_excited.json",
            calibration_bias,
            "What the model calibration finds on the model's own aircraft, whose every "
            "parameter is 0, with and without the flights' turbulence and sensor noise "
            "(docs/model_calibration.md)."),
    Section("Airspeed schedule", "airspeed_schedule.json",
            "python -m studies.airspeed_schedule --json docs/airspeed_schedule.json",
            airspeed_schedule,
            "The detector calibrated at one airspeed, at several without and with the "
            "airspeed schedule, and tested at airspeeds it did not see (docs/detector.md)."),
    Section("Guidance", "guidance.json",
            "python -m benchmarks.bench_guidance --json docs/guidance.json", guidance,
            "The default route flown with the course vector field and with the paper's MPC "
            "guidance, in calm air and in wind (docs/simulator.md)."),
    Section("Campaigns", "campaigns.json",
            "python -m benchmarks.bench_campaigns --json docs/campaigns.json", campaigns,
            "The campaign layer: flights in one process against local Dask workers, the "
            "per-task cost, and the plan for a large map (docs/performance.md)."),
    Section("Failures in simulation", "failure_kinds_*.json",
            "python -m studies.failure_kinds --vehicle carbon_z --first-seed 901 --json "
            "docs/failure_kinds_carbon_z.json && python -m studies.failure_kinds --vehicle "
            "aerosonde --first-seed 901 --json docs/failure_kinds_aerosonde.json",
            failure_kinds,
            "ALFA's failure kinds (surfaces stuck at 0, the engine cut) and the seven model "
            "faults (steps and ramps) seeded into each vehicle's fault-free flights at onsets "
            "of 60-120 s, the detector offline with the vehicle's shipped calibration and "
            "defaults (the fast test and the template test beside the self-tuning one), on "
            "seeds from 901: not the dev seeds (from 501) that chose the fast test's settings "
            "and learned the signatures and templates. "
            "detectable_within_5_s: the flights whose fault, against its twin flown without "
            "it, moves the generators' residuals within 5 s by the matched filter's "
            "signal-to-noise ratio for 90 % detection at 5 % false alarms (2.93), white noise "
            "assumed, one test at the known onset allowed a 5 % false-alarm rate; "
            "sliding_bound_found: of those, the ones the same filter finds when told the "
            "fault's signature but not its onset, slid over the flights with the threshold "
            "none of the 20 fault-free flights reaches (the targets' false-alarm level), on "
            "the residuals and on them whitened by their own AR(4) model: where "
            "it finds fewer than 90 % of the detectable, a detector, told less, is not "
            "expected to (docs/detector.md); "
            "detectable_found_within_5_s: of the detectable, the ones the detector finds "
            "within 5 s; "
            "median_bound_delay_s: when that ratio is reached; named_right: the found flights "
            "whose first alarm names the failed part (aileron, elevator, rudder, engine; "
            "docs/detector.md)."),
    Section("The Carbon-Z model on ALFA flights", "alfa_model_fit.json",
            "python -m studies.alfa_model_fit ALFA/ --vehicle carbon_z --json "
            "docs/alfa_model_fit.json", alfa_model_fit,
            "The Carbon-Z's model stepped along ALFA's five no-failure flights (the autopilot's "
            "outputs, its wind estimate), as shipped and as calibrated on the other days' "
            "flights, against the noise the simulator assumes (docs/aircraft.md)."),
    Section("ALFA benchmark", "alfa_benchmark.json",
            "python scripts/alfa_benchmark.py ALFA/ --json "
            "docs/alfa_benchmark.json", alfa_benchmark,
            "The detector on 20 labelled real flights of CMU's ALFA dataset, each screened "
            "with a calibration from the other flights' fault-free parts (docs/flight_logs.md)."),
    Section("ALFA benchmark leaving a day out", "alfa_benchmark_days.json",
            "python scripts/alfa_benchmark.py ALFA/ --leave-out day --json "
            "docs/alfa_benchmark_days.json", alfa_benchmark,
            "The same flights, each day's flights screened with a calibration from the other "
            "four days' flights: what a new day (its weather, trims and sensor offsets) brings."),
)


def section(docs: Path, entry: Section) -> list[str]:
    """The section's lines: its heading, text, command and each source file's tables."""
    lines = [f"## {entry.title}", "", entry.text, "", "Regenerate with (from the repository "
             "root, after `source scripts/env.sh`):", "", "```sh", entry.command, "```", ""]
    files = sorted(docs.glob(entry.source))
    if not files:
        return [*lines, f"Not measured in this checkout: no `docs/{entry.source}`. Run the "
                "command above, then `python tools/results_page.py`.", ""]
    for path in files:
        lines += [f"Source: `docs/{path.name}`.", ""]
        lines += entry.render(json.loads(path.read_text()))
    return lines


def render(docs: Path = DOCS) -> str:
    """The whole page for the JSON files in docs."""
    lines = ["# Results", "",
             "Every measured figure of the project, generated by `python tools/results_page.py` "
             "from the JSON files in docs/; do not edit by hand. Figures depend on the machine: "
             "compare rows within one section, not across machines.", "",
             *(f"- [{entry.title}](#{entry.title.lower().replace(' ', '-')})"
               for entry in SECTIONS), ""]
    for entry in SECTIONS:
        lines += section(docs, entry)
    return "\n".join(lines).rstrip("\n") + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Write DOCS/results.md, or with --check compare it: the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="exit 1 when the page differs from what would be generated")
    parser.add_argument("--docs", type=Path, default=DOCS,
                        help="folder of the JSON files and of results.md (default: docs/)")
    arguments = parser.parse_args(argv)
    page = arguments.docs / PAGE
    wanted = render(arguments.docs)
    if arguments.check:
        if not page.is_file() or page.read_text() != wanted:
            print(f"results_page.py: {page} is out of date: run python tools/results_page.py",
                  file=sys.stderr)
            return 1
        return 0
    page.write_text(wanted)
    print(f"results_page.py: wrote {page}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
