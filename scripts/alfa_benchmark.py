#!/usr/bin/env python3
"""The detector benchmarked on ALFA's real flights (docs/flight_logs.md, "Benchmark").

    python scripts/alfa_benchmark.py ALFA_FOLDER [--calibrate-on FOLDER] [--json FILE]
        [--airframe FILE] [--generators NAMES] [--schedule auto|none]
        [--false-alarm-probability 0.01] [--forgetting-factor F] [--window M] [--settle-s S]

ALFA_FOLDER holds flight folders in ALFA's processed layout (../shared/alfa/flights). Each
labelled flight is read with the airframe (default the shipped carbon_z_alfa.yaml), its
truth from its failure_status files; an unlabelled one (no_ground_truth) is left out, said.
Without --calibrate-on: leave one flight out, each flight screened with a calibration from
the fault-free parts of all the others (flight_logs.benchmark). With it: one calibration
from the fault-free parts of FOLDER's flights, every flight of ALFA_FOLDER screened with it.
Calibrations use detector_node's window, ALFA_FORGETTING_FACTOR and ALFA_SETTLE_S unless
given (screen_logs.py takes such a calibration; detector_node, made for 0.995, refuses it),
and the named generators (default ALFA_GENERATORS: the roll, pitch and climb tracking
generators, which read the autopilot's intent and the aircraft's response, not the outputs
ALFA's injection pins; the propulsion channel reads the throttle output an engine failure
cuts, so it would count the injection). --schedule auto schedules the parameters on airspeed
(the ground speed less the wind where the log has no airspeed) when the calibration flights
span enough of it; the default is none (measured: the same flights found, three engine
failures first on roll_tracking instead of climb_tracking, delays 0.6 s shorter on
average).

Prints a line per flight, the table per failure kind and the summary, counted as ALFA's
evaluator counts (a first alarm later than 5 s after the onset is a miss) and at any delay;
--json writes DESIGN.md's benchmark record (`flights`, `summary` with `within_limit`,
`any_delay` and `by_kind`, and the settings). Exit status 0; 2 bad input (one line); 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from uav_common.package_data import config_path, default_parameters
from uav_fault_estimator.campaigns import (
    CampaignOptions,
    add_campaign_arguments,
    campaign_options,
    run_campaign,
)
from uav_fault_estimator.detection.calibration import (
    DEFAULT_SAMPLE_PERIOD_S,
    Calibration,
)
from uav_fault_estimator.detection.calibration_fit import calibrate
from uav_fault_estimator.detection.detector import DetectorFlight
from uav_fault_estimator.detection.generators import generator_names
from uav_fault_estimator.flight_logs.benchmark import (
    ONSET_MARGIN_S,
    LabelledFlight,
    calibrated_on,
    leave_one_out,
)
from uav_fault_estimator.flight_logs.evaluation import (
    ALFA_DETECTION_LIMIT_S,
    OUTCOME_HEADING,
    alfa_summary,
    kind_lines,
    outcome_dict,
    outcome_line,
    summary_line,
)
from uav_fault_estimator.flight_logs.ground_truth import alfa_truth, is_alfa_flight
from uav_fault_estimator.flight_logs.readers import log_paths
from uav_fault_estimator.flight_logs.replay import ReplayTask, replay_of

PROGRAM = "alfa_benchmark.py"
ALFA_GENERATORS = ("roll_tracking", "pitch_tracking", "climb_tracking")
# Chosen on the 20 labelled flights, leave one flight out (docs/flight_logs.md): most of the
# logs run 11-20 s after an onset, which 0.995's memory (about 40 s) outlasts; at 0.98 (10 s)
# the climb channel's parameters move within the log, at 0.97 recall falls again. One
# no-failure flight lasts 29.9 s: 30 s of settling would never test it.
ALFA_FORGETTING_FACTOR = 0.98
ALFA_SETTLE_S = 15.0
DEFAULT_AIRFRAME = config_path("uav_fault_estimator", "airframes/carbon_z_alfa.yaml")


class BadInputError(Exception):
    """Input the user must mend: exit status 2 with the message as one line."""


def labelled_flights(folder: Path, airframe: Path,
                     options: CampaignOptions) -> list[LabelledFlight]:
    """The labelled ALFA flights in folder on the detector's grid, read where options say;
    the unlabelled said and left out. BadInputError for a folder without ALFA flights or
    flights that cannot be read (a line each, once the others are read)."""
    try:
        paths = [path for path in log_paths([folder]) if is_alfa_flight(path)]
        if not paths:
            raise BadInputError(f"{folder}: no ALFA flight folder in it")
        truths = {path: alfa_truth(path) for path in paths}
    except ValueError as error:
        raise BadInputError(str(error)) from None
    for path, truth in truths.items():
        if not truth.labelled:
            print(f"left out, unlabelled: {path.name}")
    labelled = [path for path, truth in truths.items() if truth.labelled]
    read = run_campaign(replay_of, [ReplayTask.of(path, airframe, None, DEFAULT_SAMPLE_PERIOD_S)
                                    for path in labelled], "ALFA flights", options)
    if read.failures:
        raise BadInputError("\n".join(failure.message for failure in read.failures))
    return [LabelledFlight(path.name, replay.inputs, truths[path])
            for path, replay in zip(labelled, read.results, strict=True)]


def calibrator(arguments: argparse.Namespace, airframe_name: str):
    """calibrate(fault-free parts) -> Calibration with the benchmark's settings."""
    def calibrated(flights: Sequence[DetectorFlight]) -> Calibration:
        def made(scheduled: bool) -> Calibration:
            return calibrate(flights, DEFAULT_SAMPLE_PERIOD_S, arguments.forgetting_factor,
                             arguments.window, arguments.settle_s, airframe=airframe_name,
                             scheduled=scheduled, generators=arguments.generators)
        if arguments.schedule == "auto":
            try:
                return made(True)
            except ValueError:  # too narrow a span of airspeeds: no schedule
                pass
        return made(False)

    return calibrated


def run(arguments: argparse.Namespace) -> dict:
    """The benchmark's record (printed as it goes)."""
    started = time.monotonic()
    flights = labelled_flights(arguments.alfa_folder, arguments.airframe,
                               campaign_options(arguments))
    calibrated = calibrator(arguments, "carbon_z_alfa")
    try:
        if arguments.calibrate_on is None:
            outcomes = leave_one_out(flights, calibrated, arguments.false_alarm_probability)
        else:
            calibration_flights = labelled_flights(arguments.calibrate_on, arguments.airframe,
                                                   campaign_options(arguments))
            outcomes = calibrated_on(calibration_flights, flights, calibrated,
                                     arguments.false_alarm_probability)
    except ValueError as error:  # a generator without samples to fit it on
        raise BadInputError(str(error)) from None
    summary = alfa_summary(outcomes)
    print(OUTCOME_HEADING)
    print("\n".join(map(outcome_line, outcomes)))
    print("\n".join(kind_lines(summary)))
    print(f"within {ALFA_DETECTION_LIMIT_S:g} s (ALFA's evaluator): "
          f"{summary_line(summary['within_limit'])}")
    print(f"at any delay: {summary_line(summary['any_delay'])}")
    return {
        "alfa_folder": str(arguments.alfa_folder),
        "mode": ("leave_one_flight_out" if arguments.calibrate_on is None
                 else f"calibrated_on {arguments.calibrate_on}"),
        "generators": list(arguments.generators),
        "schedule": arguments.schedule,
        "false_alarm_probability": arguments.false_alarm_probability,
        "forgetting_factor": arguments.forgetting_factor,
        "window": arguments.window,
        "settle_s": arguments.settle_s,
        "onset_margin_s": ONSET_MARGIN_S,
        "wall_time_s": round(time.monotonic() - started, 1),
        "flights": [outcome_dict(outcome) for outcome in outcomes],
        "summary": summary,
    }


def parser() -> argparse.ArgumentParser:
    top = argparse.ArgumentParser(prog=PROGRAM, description=__doc__.splitlines()[0])
    top.add_argument("alfa_folder", type=Path, metavar="ALFA_FOLDER")
    top.add_argument("--calibrate-on", type=Path, default=None, metavar="FOLDER")
    top.add_argument("--json", type=Path, default=None, metavar="FILE")
    top.add_argument("--airframe", type=Path, default=DEFAULT_AIRFRAME)
    top.add_argument("--generators", type=generator_names, default=ALFA_GENERATORS)
    top.add_argument("--schedule", choices=("auto", "none"), default="none")
    top.add_argument("--false-alarm-probability", type=float, default=0.01)
    top.add_argument("--forgetting-factor", type=float, default=ALFA_FORGETTING_FACTOR)
    top.add_argument("--window", type=int, default=default_parameters(
        "uav_fault_estimator", "detector_node.yaml")["window"])
    top.add_argument("--settle-s", type=float, default=ALFA_SETTLE_S)
    add_campaign_arguments(top)
    return top


def main(argv: Sequence[str] | None = None) -> int:
    arguments = parser().parse_args(argv)
    try:
        record = run(arguments)
        if arguments.json is not None:
            arguments.json.write_text(json.dumps(record, indent=2) + "\n")
    except BadInputError as error:
        print(f"{PROGRAM}: {error}", file=sys.stderr)
        return 2
    except OSError as error:
        print(f"{PROGRAM}: cannot write {arguments.json}: {error.strerror}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
