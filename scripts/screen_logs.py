#!/usr/bin/env python3
"""Screen flight logs with the self-tuning detector: calibrate it from fault-free logs of one
airframe, then screen other logs of it for alarms (docs/detector.md).

    python scripts/screen_logs.py calibrate FAULT_FREE_LOG... --airframe AIRFRAME.yaml \\
        --out CAL.yaml [--schedule auto|airspeed|none]
    python scripts/screen_logs.py screen LOG... --calibration CAL.yaml \\
        --airframe AIRFRAME.yaml --out DIR [--false-alarm-probability 0.01]

A LOG is a PX4 .ulg, a ROS 1 .bag, a ROS 2 bag folder or a folder of per-topic CSVs; any
other folder stands for the logs directly in it (flight_logs.readers.log_paths). Each log
is read with the airframe file's axes and outputs and put on the detector's grid
(flight_logs.replay.load_replay); its warnings are printed once (each line names the log).

calibrate: self_tuning.calibrate over the logs with the airframe's name, on the grid of
DEFAULT_SAMPLE_PERIOD_S, settling DEFAULT_SETTLE_S, with detector_node's window and
forgetting factor (config/detector_node.yaml), so that detector_node takes the file too.
--schedule auto (default): the parameters' means scheduled on airspeed when the logs'
airspeeds span enough (self_tuning.MIN_SCHEDULE_SPAN_MPS), else a line saying why and no
schedule; airspeed: a schedule or refuse; none: no schedule.

screen: per log into DIR: NAME.alarms.csv (the alarm intervals: start_s, end_s, channel,
test, samples; also printed), NAME.png (the figure), NAME.json (flight_logs.screening's
summary), and DIR/summary.json (the calibration, the settings and every log's summary).
NAME is the log's file or folder name without its suffix.

Exit status: 0 done; 2 bad input, one line (a missing or unreadable log, a folder without
logs, two logs of one name, a bad airframe file, a calibration file that is malformed, for
another airframe or for other detector settings, a schedule the logs cannot give, an output
that cannot be written); 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from uav_common.package_data import default_parameters
from uav_fault_estimator.detection.calibration import (
    DEFAULT_SAMPLE_PERIOD_S,
    DEFAULT_SETTLE_S,
    Calibration,
)
from uav_fault_estimator.detection.calibration_file import calibration_to_dict, load_calibration
from uav_fault_estimator.detection.calibration_fit import calibrate
from uav_fault_estimator.detection.detector import run_detector
from uav_fault_estimator.flight_logs.airframe import Airframe, load_airframe
from uav_fault_estimator.flight_logs.readers import log_paths
from uav_fault_estimator.flight_logs.replay import LogReplay, load_replay
from uav_fault_estimator.flight_logs.screening import (
    alarm_intervals,
    alarm_table,
    log_summary,
    plot_screening,
    write_alarm_csv,
)
from uav_fault_estimator.offline import write_calibration

PROGRAM = "screen_logs.py"
SCHEDULES = ("auto", "airspeed", "none")


class BadInputError(Exception):
    """Input the user must mend: exit status 2 with the message as one line."""


def detector_settings() -> dict:
    """detector_node's parameters (config/detector_node.yaml): its window and forgetting
    factor are what a calibration made here must match."""
    return default_parameters("uav_fault_estimator", "detector_node.yaml")


def airframe_of(path: Path) -> Airframe:
    """The airframe file, or BadInputError with its line."""
    try:
        return load_airframe(path)
    except ValueError as error:  # AirframeError and the strict reader's lines
        raise BadInputError(str(error)) from None


def load_logs(paths: Sequence[Path], airframe: Airframe,
              period_s: float) -> dict[str, LogReplay]:
    """Every log that paths name (folders expanded) on the grid of period_s [s], by name,
    each log's warnings printed once; BadInputError for a log that cannot be read or used, or
    two logs of one name (their outputs would overwrite each other)."""
    logs: dict[str, LogReplay] = {}
    try:
        for path in log_paths(paths):
            name = path.stem
            if name in logs:
                raise BadInputError(f"two logs named '{name}': {logs[name].source} and {path}; "
                               "rename one or screen them separately")
            logs[name] = load_replay(path, airframe.path, None, period_s)
            for line in logs[name].inputs.warnings:  # each names its log
                print(line)
    except ValueError as error:
        raise BadInputError(str(error)) from None
    return logs


def calibrate_logs(arguments: argparse.Namespace) -> None:
    """The calibrate command: the calibration file from the fault-free logs."""
    started = time.monotonic()
    airframe = airframe_of(arguments.airframe)
    logs = load_logs(arguments.logs, airframe, DEFAULT_SAMPLE_PERIOD_S)
    node = detector_settings()
    flights = [log.inputs.flight for log in logs.values()]

    def calibrated(scheduled: bool) -> Calibration:
        return calibrate(flights, DEFAULT_SAMPLE_PERIOD_S, node["forgetting_factor"],
                         node["window"], DEFAULT_SETTLE_S, airframe=airframe.name,
                         scheduled=scheduled)

    if arguments.schedule == "none":
        calibration = calibrated(False)
    else:
        try:
            calibration = calibrated(True)
        except ValueError as error:  # the airspeeds' span or missing airspeeds
            if arguments.schedule == "airspeed":
                raise BadInputError(f"no airspeed schedule: {error}") from None
            print(f"no airspeed schedule: {error}")
            calibration = calibrated(False)
    print(f"airspeed schedule: reference {calibration.reference_airspeed_mps:.2f} m/s"
          if calibration.scheduled else "airspeed schedule: none")
    header = (f"# Written by scripts/screen_logs.py calibrate for the airframe "
              f"'{airframe.name}' ({airframe.path}) from the fault-free logs\n"
              + "".join(f"#   {log.source}\n" for log in logs.values())
              + "# Valid for the sample period, forgetting factor and window below only.\n")
    try:
        write_calibration(arguments.out, header, calibration_to_dict(calibration),
                          f"{len(logs)} logs", time.monotonic() - started)
    except OSError as error:
        raise BadInputError(f"cannot write {arguments.out}: {error.strerror}") from None


def screen_logs(arguments: argparse.Namespace) -> None:
    """The screen command: per log its alarm table, figure and summary, and summary.json."""
    if not 0.0 < arguments.false_alarm_probability < 1.0:
        raise BadInputError(f"--false-alarm-probability {arguments.false_alarm_probability:g}: "
                       "must lie between 0 and 1")
    airframe = airframe_of(arguments.airframe)
    node = detector_settings()
    try:
        calibration = load_calibration(str(arguments.calibration), node["window"],
                                       node["forgetting_factor"], airframe.name)
    except ValueError as error:
        raise BadInputError(str(error)) from None
    period_s = calibration.sample_period_s
    logs = load_logs(arguments.logs, airframe, period_s)
    out = arguments.out
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise BadInputError(f"cannot write into {out}: {error.strerror}") from None
    summaries = []
    for name, log in logs.items():
        samples = run_detector(calibration, log.inputs.flight,
                               arguments.false_alarm_probability)
        intervals = alarm_intervals(samples, period_s)
        summary = log_summary(name, log.source, samples, period_s, log.inputs.warnings)
        counts = summary["alarm_samples"]
        print(f"{name}: {summary['samples']} samples, {summary['tested_samples']} tested; "
              "alarm samples glrt {}, parameter {}, combined {}; first combined alarm {}"
              .format(*(counts[test]["any"] for test in ("glrt", "parameter", "combined")),
                      "none" if summary["first_combined_alarm_s"] is None
                      else f"at {summary['first_combined_alarm_s']:.1f} s"))
        print(alarm_table(intervals))
        write_alarm_csv(out / f"{name}.alarms.csv", intervals)
        plot_screening(f"{name}: designed P_FA {arguments.false_alarm_probability:g} per "
                       "sample and test", log.inputs, samples, intervals, period_s,
                       out / f"{name}.png")
        (out / f"{name}.json").write_text(json.dumps(summary, indent=2) + "\n")
        summaries.append(summary)
    (out / "summary.json").write_text(json.dumps({
        "calibration": str(arguments.calibration),
        "airframe": airframe.name,
        "airspeed_schedule": calibration.scheduled,
        "sample_period_s": period_s,
        "false_alarm_probability": arguments.false_alarm_probability,
        "logs": summaries,
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
    calibrate_command.set_defaults(run=calibrate_logs)
    screen_command = commands.add_parser("screen", help="screen logs for alarms")
    screen_command.add_argument("logs", type=Path, nargs="+", metavar="LOG")
    screen_command.add_argument("--calibration", type=Path, required=True)
    screen_command.add_argument("--airframe", type=Path, required=True)
    screen_command.add_argument("--out", type=Path, required=True,
                                help="the folder for the tables, figures and summaries")
    screen_command.add_argument("--false-alarm-probability", type=float, default=0.01,
                                help="designed per sample and test (default 0.01)")
    screen_command.set_defaults(run=screen_logs)
    return top


def main(argv: Sequence[str] | None = None) -> int:
    arguments = parser().parse_args(argv)
    try:
        arguments.run(arguments)
    except BadInputError as error:
        print(f"{PROGRAM}: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
