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
import sys
from collections.abc import Sequence
from pathlib import Path

from uav_fault_estimator.campaigns.campaign import add_campaign_arguments, campaign_options
from uav_fault_estimator.campaigns.cluster_security import ClusterAddressError
from uav_fault_estimator.detection.calibration import (
    DEFAULT_FORGETTING_FACTOR,
    DEFAULT_SETTLE_S,
    DEFAULT_WINDOW,
)
from uav_fault_estimator.detection.calibration_fit import SCHEDULES
from uav_fault_estimator.detection.detector_settings import DetectorSettings
from uav_fault_estimator.detection.generators import SURFACE_GENERATORS, generator_names
from uav_fault_estimator.flight_logs.loading import BadInputError
from uav_fault_estimator.flight_logs.screening_run import (
    CalibrationRequest,
    ScreeningRequest,
    calibrate_from_logs,
    screen,
)

PROGRAM = "screen_logs.py"


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
    return top


def main(argv: Sequence[str] | None = None) -> int:
    arguments = parser().parse_args(argv)
    try:
        options = campaign_options(arguments)
        if arguments.command == "calibrate":
            calibrate_from_logs(CalibrationRequest(
                log_paths=tuple(arguments.logs), airframe_path=arguments.airframe,
                out_path=arguments.out, schedule=arguments.schedule,
                generators=arguments.generators, truth_table_path=arguments.truth,
                forgetting_factor=arguments.forgetting_factor,
                window_samples=arguments.window, settle_s=arguments.settle_s,
                campaign=options))
        else:
            screen(ScreeningRequest(
                log_paths=tuple(arguments.logs), calibration_path=arguments.calibration,
                airframe_path=arguments.airframe, out_dir=arguments.out,
                false_alarm_probability=arguments.false_alarm_probability,
                truth_table_path=arguments.truth, campaign=options))
    except (BadInputError, ClusterAddressError) as error:
        print(f"{PROGRAM}: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
