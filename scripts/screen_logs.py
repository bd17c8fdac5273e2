#!/usr/bin/env python3
"""Screen flight logs with the self-tuning detector: calibrate it from fault-free logs of one
airframe, then screen other logs of it for alarms, against their ground truth where it is
known (docs/flight_logs.md).

    python scripts/screen_logs.py calibrate FAULT_FREE_LOG... --airframe AIRFRAME.yaml \\
        --out CAL.yaml [--schedule auto|airspeed|none] [--generators roll,pitch,yaw]
        [--truth TABLE.csv] [--forgetting-factor F] [--window M] [--settle-s S]
    python scripts/screen_logs.py screen LOG... --calibration CAL.yaml \\
        --airframe AIRFRAME.yaml --out DIR [--false-alarm-probability 0.01] [--truth TABLE.csv]

A LOG is a PX4 .ulg, a ROS 1 .bag, a ROS 2 bag folder or a folder of per-topic CSVs (ALFA's
flight folders among them); any other folder stands for the logs directly in it
(flight_logs.readers.log_paths). Each log is read with the airframe file's axes and outputs
and put on the detector's grid (flight_logs.replay.load_replay); its warnings are printed
once (each line names the log).

Ground truth (flight_logs.ground_truth): the --truth table's row of each log, else an ALFA
flight folder's own failure_status files. calibrate learns from the fault-free part of each
log with a known truth (a failure flight up to its onset less benchmark.ONSET_MARGIN_S), and
from the whole of a log without one. screen holds each log with a known truth against it
(flight_logs.evaluation): the table of outcomes and its summary are printed and written to
summary.json, and the figure marks the onset.

calibrate: calibration_fit.calibrate over the logs with the airframe's name and the named
generators (detection.generators; default the paper's roll, pitch, yaw), on the grid of
DEFAULT_SAMPLE_PERIOD_S, settling DEFAULT_SETTLE_S, with DEFAULT_WINDOW and
DEFAULT_FORGETTING_FACTOR (detection.calibration, as the shipped calibrations are made);
--forgetting-factor, --window and --settle-s make one with other settings (a calibration
carries its settings: detector_node and screen run it with them).
--schedule auto (default): the parameters' means scheduled on airspeed when the logs'
airspeeds span enough (calibration.MIN_SCHEDULE_SPAN_MPS), else a line saying why and no
schedule; airspeed: a schedule or refuse; none: no schedule.

screen: per log into DIR: NAME.alarms.csv (the alarm intervals: start_s, end_s, channel,
test, samples, also printed, and their ends in the log's clock, start_stamp_s and
end_stamp_s), NAME.png (the figure), NAME.json (flight_logs.screening's summary, with the
log's start stamp and, with a truth, its outcome), and DIR/summary.json
(the calibration, the settings, every log's summary and, with truths, the evaluation).
NAME is the log's file or folder name without its suffix.

Exit status: 0 done; 2 bad input, one line (a missing or unreadable log, a folder without
logs, two logs of one name, a bad airframe file or truth table, a calibration file that is
malformed or for another airframe, a schedule the logs cannot
give, unknown generators, an output that cannot be written); 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

from uav_aircraft.airframe import Airframe, load_airframe
from uav_fault_estimator.campaigns.campaign import (
    CampaignOptions,
    add_campaign_arguments,
    campaign_options,
    run_campaign,
)
from uav_fault_estimator.campaigns.cluster_security import ClusterAddressError
from uav_fault_estimator.detection.calibration import (
    DEFAULT_FORGETTING_FACTOR,
    DEFAULT_SAMPLE_PERIOD_S,
    DEFAULT_SETTLE_S,
    DEFAULT_WINDOW,
)
from uav_fault_estimator.detection.calibration_file import calibration_to_dict, read_calibration
from uav_fault_estimator.detection.calibration_fit import (
    SCHEDULES,
    ScheduleError,
    calibrate_scheduled,
)
from uav_fault_estimator.detection.detector import run_detector
from uav_fault_estimator.detection.detector_settings import DetectorSettings
from uav_fault_estimator.detection.generators import SURFACE_GENERATORS, generator_names
from uav_fault_estimator.flight_logs.benchmark import LabelledFlight, fault_free_part
from uav_fault_estimator.flight_logs.evaluation import (
    ALFA_DETECTION_LIMIT_S,
    OUTCOME_HEADING,
    evaluation_summary,
    flight_outcome,
    outcome_dict,
    outcome_line,
    summary_line,
)
from uav_fault_estimator.flight_logs.ground_truth import (
    FlightTruth,
    flight_truth,
    read_truth_table,
)
from uav_fault_estimator.flight_logs.readers import log_paths
from uav_fault_estimator.flight_logs.replay import LogReplay, ReplayTask, replay_of
from uav_fault_estimator.flight_logs.screening import (
    alarm_intervals,
    alarm_table,
    log_summary,
    plot_screening,
    write_alarm_csv,
)
from uav_fault_estimator.reporting.calibration_output import write_calibration

PROGRAM = "screen_logs.py"


class BadInputError(Exception):
    """Input the user must mend: exit status 2 with the message as one line."""


def airframe_of(path: Path) -> Airframe:
    """The airframe file, or BadInputError with its line."""
    try:
        return load_airframe(path)
    except ValueError as error:  # AirframeError and the strict reader's lines
        raise BadInputError(str(error)) from None


class LoadedLog(NamedTuple):
    """A log on the grid and its ground truth (None: not known)."""

    replay: LogReplay
    truth: FlightTruth | None


def load_logs(paths: Sequence[Path], airframe: Airframe, period_s: float,
              truth_table: Path | None, options: CampaignOptions) -> dict[str, LoadedLog]:
    """Every log that paths name (folders expanded) on the grid of period_s [s], read where
    options say, with its truth (the table's, else an ALFA folder's own), by name, each
    log's warnings printed once; BadInputError for a bad truth table, two logs of one name
    (their outputs would overwrite each other), or logs that cannot be read or used (a line
    each, once every other log is read)."""
    try:
        table = None if truth_table is None else read_truth_table(truth_table)
        found = log_paths(paths)
    except ValueError as error:
        raise BadInputError(str(error)) from None
    named: dict[str, Path] = {}
    for path in found:
        if path.stem in named:
            raise BadInputError(f"two logs named '{path.stem}': {named[path.stem]} and {path}; "
                                "rename one or screen them separately")
        named[path.stem] = path
    tasks = [ReplayTask.of(path, airframe.path, None, period_s) for path in named.values()]
    read = run_campaign(replay_of, tasks, "logs", options)
    if read.failures:
        raise BadInputError("\n".join(failure.message for failure in read.failures))
    logs = {}
    for (name, path), replay in zip(named.items(), read.results, strict=True):
        logs[name] = LoadedLog(replay, flight_truth(path, name, table))
        for line in replay.inputs.warnings:  # each names its log
            print(line)
    return logs


def calibrate_logs(arguments: argparse.Namespace) -> None:
    """The calibrate command: the calibration file from the fault-free logs."""
    started = time.monotonic()
    airframe = airframe_of(arguments.airframe)
    logs = load_logs(arguments.logs, airframe, DEFAULT_SAMPLE_PERIOD_S, arguments.truth,
                     campaign_options(arguments))
    unlabelled = [name for name, log in logs.items()
                  if log.truth is not None and not log.truth.labelled]
    if unlabelled:
        print(f"left out, unlabelled: {', '.join(unlabelled)}")
    parts = [log.replay.inputs.flight if log.truth is None else
             fault_free_part(LabelledFlight(name, log.replay.inputs, log.truth))
             for name, log in logs.items() if name not in unlabelled]
    flights = [part for part in parts if part is not None]

    try:
        calibration, unscheduled = calibrate_scheduled(
            flights, arguments.schedule, sample_period_s=DEFAULT_SAMPLE_PERIOD_S,
            forgetting_factor=arguments.forgetting_factor, window=arguments.window,
            settle_s=arguments.settle_s, airframe=airframe.name,
            generators=arguments.generators)
    except ScheduleError as error:
        raise BadInputError(f"no airspeed schedule: {error}") from None
    except ValueError as error:
        raise BadInputError(str(error)) from None
    if unscheduled:
        print(f"no airspeed schedule: {unscheduled}")
    print(f"airspeed schedule: reference {calibration.reference_airspeed_mps:.2f} m/s"
          if calibration.scheduled else "airspeed schedule: none")
    header = (f"# Written by scripts/screen_logs.py calibrate for the airframe "
              f"'{airframe.name}' ({airframe.path}) from the fault-free logs\n"
              + "".join(f"#   {log.replay.source}\n" for log in logs.values())
              + "# Valid for the sample period, forgetting factor and window below only.\n")
    try:
        write_calibration(arguments.out, header, calibration_to_dict(calibration),
                          f"{len(flights)} logs", time.monotonic() - started)
    except OSError as error:
        raise BadInputError(f"cannot write {arguments.out}: {error.strerror}") from None


def screen_logs(arguments: argparse.Namespace) -> None:
    """The screen command: per log its alarm table, figure and summary, and summary.json."""
    if not 0.0 < arguments.false_alarm_probability < 1.0:
        raise BadInputError(f"--false-alarm-probability {arguments.false_alarm_probability:g}: "
                       "must lie between 0 and 1")
    airframe = airframe_of(arguments.airframe)
    try:
        calibration = read_calibration(str(arguments.calibration), airframe.name)
    except ValueError as error:
        raise BadInputError(str(error)) from None
    period_s = calibration.sample_period_s
    channels = calibration.channel_names
    logs = load_logs(arguments.logs, airframe, period_s, arguments.truth,
                     campaign_options(arguments))
    out = arguments.out
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise BadInputError(f"cannot write into {out}: {error.strerror}") from None
    summaries, outcomes = [], []
    for name, (log, truth) in logs.items():
        inputs = log.inputs
        samples = run_detector(calibration, inputs.flight, arguments.false_alarm_probability)
        intervals = alarm_intervals(samples, channels, period_s)
        summary = log_summary(name, log.source, samples, channels, period_s, inputs.warnings,
                              inputs.start_stamp_s)
        counts = summary["alarm_samples"]
        print(f"{name}: {summary['samples']} samples, {summary['tested_samples']} tested; "
              "alarm samples glrt {}, parameter {}, combined {}; first combined alarm {}"
              .format(*(counts[test]["any"] for test in ("glrt", "parameter", "combined")),
                      "none" if summary["first_combined_alarm_s"] is None
                      else f"at {summary['first_combined_alarm_s']:.1f} s"))
        print(alarm_table(intervals))
        onset_s = None
        if truth is not None and truth.labelled:
            outcome = flight_outcome(name, truth, samples, channels, inputs.start_stamp_s)
            summary["outcome"] = outcome_dict(outcome)
            outcomes.append(outcome)
            if truth.onset_stamp_s is not None:
                onset_s = truth.onset_stamp_s - inputs.start_stamp_s
        write_alarm_csv(out / f"{name}.alarms.csv", intervals, inputs.start_stamp_s)
        plot_screening(f"{name}: designed P_FA {arguments.false_alarm_probability:g} per "
                       "sample and test", inputs, samples, channels, intervals, period_s,
                       out / f"{name}.png", onset_s, ALFA_DETECTION_LIMIT_S)
        (out / f"{name}.json").write_text(json.dumps(summary, indent=2) + "\n")
        summaries.append(summary)
    evaluation = None
    if outcomes:
        evaluation = evaluation_summary(outcomes)
        print(OUTCOME_HEADING)
        print("\n".join(map(outcome_line, outcomes)))
        print(summary_line(evaluation))
    (out / "summary.json").write_text(json.dumps({
        "calibration": str(arguments.calibration),
        "airframe": airframe.name,
        "channels": list(channels),
        "airspeed_schedule": calibration.scheduled,
        "sample_period_s": period_s,
        "false_alarm_probability": arguments.false_alarm_probability,
        "logs": summaries,
        "evaluation": evaluation,
    }, indent=2) + "\n")
    print(f"screened {len(summaries)} logs into {out}")


def parser() -> argparse.ArgumentParser:
    """The command line: calibrate and screen."""
    top = argparse.ArgumentParser(prog=PROGRAM, description=__doc__.splitlines()[0])
    commands = top.add_subparsers(dest="command", required=True)
    calibrate_command = commands.add_parser("calibrate", help="calibrate from fault-free logs")
    calibrate_command.add_argument("logs", type=Path, nargs="+", metavar="FAULT_FREE_LOG")
    calibrate_command.add_argument("--airframe", type=Path, required=True)
    calibrate_command.add_argument("--out", type=Path, required=True,
                                   help="the calibration file to write")
    calibrate_command.add_argument("--schedule", choices=SCHEDULES, default="auto")
    calibrate_command.add_argument("--generators", type=generator_names,
                                   default=SURFACE_GENERATORS,
                                   help="comma-separated (default roll,pitch,yaw)")
    calibrate_command.add_argument("--truth", type=Path, default=None,
                                   help="truth table: a failure log's part from its onset "
                                        "on is left out")
    calibrate_command.add_argument("--forgetting-factor", type=float,
                                   default=DEFAULT_FORGETTING_FACTOR,
                                   help="lambda_f of the RLS (default %(default)g)")
    calibrate_command.add_argument("--window", type=int, default=DEFAULT_WINDOW,
                                   help="M, the GLRT window [samples] (default %(default)d)")
    calibrate_command.add_argument("--settle-s", type=float, default=DEFAULT_SETTLE_S,
                                   help="no test this long after a start [s]")
    add_campaign_arguments(calibrate_command)
    calibrate_command.set_defaults(run=calibrate_logs)
    screen_command = commands.add_parser("screen", help="screen logs for alarms")
    screen_command.add_argument("logs", type=Path, nargs="+", metavar="LOG")
    screen_command.add_argument("--calibration", type=Path, required=True)
    screen_command.add_argument("--airframe", type=Path, required=True)
    screen_command.add_argument("--out", type=Path, required=True,
                                help="the folder for the tables, figures and summaries")
    screen_command.add_argument("--false-alarm-probability", type=float,
                                default=DetectorSettings().false_alarm_probability,
                                help="designed per sample and test (default %(default)g)")
    screen_command.add_argument("--truth", type=Path, default=None,
                                help="truth table (log,failure,onset_stamp_s); without it "
                                     "ALFA folders' own failure_status files")
    add_campaign_arguments(screen_command)
    screen_command.set_defaults(run=screen_logs)
    return top


def main(argv: Sequence[str] | None = None) -> int:
    arguments = parser().parse_args(argv)
    try:
        arguments.run(arguments)
    except (BadInputError, ClusterAddressError) as error:
        print(f"{PROGRAM}: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
