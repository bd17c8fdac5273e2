#!/usr/bin/env python3
"""The detector benchmarked on ALFA's real flights, its peer beside it (docs/flight_logs.md).

    python scripts/alfa_benchmark.py ALFA_FOLDER [--leave-out flight|day]
        [--calibrate-on FOLDER] [--no-peer] [--json FILE] [--figures DIR] [--airframe FILE]
        [--generators NAMES] [--schedule auto|none] [--false-alarm-probability 0.01]
        [--forgetting-factor F] [--window M] [--settle-s S]

ALFA_FOLDER holds flight folders in ALFA's processed layout (docs/flight_logs.md). Each
labelled flight is read with the airframe (default the shipped carbon_z_alfa.yaml), its
truth from its failure_status files; an unlabelled one (no_ground_truth) is left out, said.
Without --calibrate-on: leave one flight out (each flight screened with a calibration from
the fault-free parts of all the others) or, --leave-out day, one day out (each day's
flights with a calibration from the other days' flights); flight_logs.benchmark. With it:
one calibration from the fault-free parts of FOLDER's flights, every flight of ALFA_FOLDER
screened with it. Calibrations use the default window of a calibration
(detection.calibration), ALFA_FORGETTING_FACTOR and ALFA_SETTLE_S unless given (a
calibration carries them: screen_logs.py and detector_node run it with them), and the named
generators (default ALFA_GENERATORS: the roll, pitch and
climb tracking generators, which read the autopilot's intent and the aircraft's response,
not the outputs ALFA's injection pins, and the lateral specific force; the propulsion
channel reads the throttle output an engine failure cuts, so it would count the injection).
--schedule auto schedules the parameters on airspeed (the ground speed less the wind where
the log has no airspeed) when the calibration flights span enough of it; the default is none
(measured: the same flights found, three engine failures first on roll_tracking instead of
climb_tracking, delays 0.6 s shorter on average). The peer, Keipour et al.'s RLS detector
(uav_fault_estimator.flight_logs.keipour2019_rls), runs on the same flights in the same
folds unless --no-peer.

Prints, for the project's detector and then the peer, a line per flight, the table per
failure kind and the summary, counted as ALFA's evaluator counts (a first alarm later than
5 s after the onset is a miss) and at any delay; --json writes the benchmark's record
(`flights`, `summary` with the counts at any delay, the same within 5 s as `tp_5s`, ...,
and `by_kind`; `peers`; the settings: docs/design.md#the-alfa-benchmarks-record);
--figures draws each flight as screen_logs.py does, with the onset and the 5 s after it
marked. Exit status 0; 2 bad input (one line); 1 otherwise.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from uav_fault_estimator.campaigns.campaign import add_campaign_arguments, campaign_options
from uav_fault_estimator.campaigns.cluster_security import ClusterAddressError
from uav_fault_estimator.detection.calibration import DEFAULT_WINDOW
from uav_fault_estimator.detection.detector_settings import DetectorSettings
from uav_fault_estimator.detection.generators import generator_names
from uav_fault_estimator.flight_logs.alfa_run import (
    ALFA_FORGETTING_FACTOR,
    ALFA_GENERATORS,
    ALFA_SETTLE_S,
    DEFAULT_AIRFRAME,
    LEAVE_OUT,
    AlfaBenchmarkRequest,
    run_benchmark,
)
from uav_fault_estimator.flight_logs.loading import BadInputError

PROGRAM = "alfa_benchmark.py"


def parser() -> argparse.ArgumentParser:
    top = argparse.ArgumentParser(prog=PROGRAM, description=__doc__.splitlines()[0])
    top.add_argument("alfa_folder", type=Path, metavar="ALFA_FOLDER")
    top.add_argument("--calibrate-on", type=Path, default=None, metavar="FOLDER")
    top.add_argument("--leave-out", choices=LEAVE_OUT, default="flight")
    top.add_argument("--no-peer", action="store_true")
    top.add_argument("--figures", type=Path, default=None, metavar="DIR")
    top.add_argument("--json", type=Path, default=None, metavar="FILE")
    top.add_argument("--airframe", type=Path, default=DEFAULT_AIRFRAME)
    top.add_argument("--generators", type=generator_names, default=ALFA_GENERATORS)
    top.add_argument("--schedule", choices=("auto", "none"), default="none")
    top.add_argument("--false-alarm-probability", type=float,
                     default=DetectorSettings().false_alarm_probability)
    top.add_argument("--forgetting-factor", type=float, default=ALFA_FORGETTING_FACTOR)
    top.add_argument("--window", type=int, default=DEFAULT_WINDOW)
    top.add_argument("--settle-s", type=float, default=ALFA_SETTLE_S)
    add_campaign_arguments(top)
    return top


def main(argv: Sequence[str] | None = None) -> int:
    arguments = parser().parse_args(argv)
    try:
        run_benchmark(AlfaBenchmarkRequest(
            alfa_folder=arguments.alfa_folder, calibrate_on=arguments.calibrate_on,
            leave_out=arguments.leave_out, with_peer=not arguments.no_peer,
            figures_dir=arguments.figures, json_path=arguments.json,
            airframe_path=arguments.airframe, generators=arguments.generators,
            schedule=arguments.schedule,
            false_alarm_probability=arguments.false_alarm_probability,
            forgetting_factor=arguments.forgetting_factor, window_samples=arguments.window,
            settle_s=arguments.settle_s, campaign=campaign_options(arguments)))
    except (BadInputError, ClusterAddressError) as error:
        print(f"{PROGRAM}: {error}", file=sys.stderr)
        return 2
    except OSError as error:
        print(f"{PROGRAM}: cannot write {error.filename}: {error.strerror}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
