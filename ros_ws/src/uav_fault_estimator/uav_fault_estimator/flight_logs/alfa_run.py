"""The detector benchmarked on ALFA's real flights, its peer beside it: the run of
scripts/alfa_benchmark.py (its docstring is the user's account, and docs/flight_logs.md),
over the folds of benchmark.py. Prints what the command prints, draws its figures and
writes its record; input the user must mend is a loading.BadInputError with its line. No
ROS here.
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from uav_aircraft.vehicles import load_vehicle

from uav_fault_estimator.campaigns.campaign import CampaignOptions
from uav_fault_estimator.detection.calibration import DEFAULT_SAMPLE_PERIOD_S, Calibration
from uav_fault_estimator.detection.calibration_fit import calibrate_scheduled
from uav_fault_estimator.detection.detector import DetectorFlight, DetectorSample
from uav_fault_estimator.flight_logs import keipour2019_rls as peer
from uav_fault_estimator.flight_logs.benchmark import (
    ONSET_MARGIN_S,
    Calibrate,
    Fold,
    LabelledFlight,
    Seen,
    flight_day,
    leave_out_folds,
    screened_in_folds,
)
from uav_fault_estimator.flight_logs.evaluation import (
    ALFA_DETECTION_LIMIT_S,
    OUTCOME_HEADING,
    FlightOutcome,
    alfa_summary,
    kind_lines,
    outcome_dict,
    outcome_line,
    summary_line,
    within_counts,
)
from uav_fault_estimator.flight_logs.ground_truth import FlightTruth, alfa_truth, is_alfa_flight
from uav_fault_estimator.flight_logs.loading import (
    BadInputError,
    read_in_campaign,
    replays_on_grid,
)
from uav_fault_estimator.flight_logs.readers import log_paths
from uav_fault_estimator.flight_logs.screening import alarm_intervals, plot_screening

ALFA_GENERATORS = ("roll_tracking", "pitch_tracking", "climb_tracking", "lateral_force")
# Chosen on the 20 labelled flights leaving one day out (docs/flight_logs.md): lateral_force
# finds the stuck rudder on its own channel, sooner; with it, 0.95 (about 4 s of memory)
# finds as many within 5 s as 0.98 and more at any delay, without a false alarm. Most logs
# run 11-20 s after an onset, which 0.995's memory (about 40 s) outlasts. One no-failure
# flight lasts 29.9 s: 30 s of settling would never test it.
ALFA_FORGETTING_FACTOR = 0.95
ALFA_SETTLE_S = 15.0
# ALFA's aircraft's airframe: the default file the flights are read with, and the name its
# calibrations carry.
ALFA_AIRFRAME = "carbon_z_alfa"
DEFAULT_AIRFRAME = load_vehicle("carbon_z").airframe_files[ALFA_AIRFRAME]
LEAVE_OUT = ("flight", "day")


@dataclass(frozen=True)
class AlfaBenchmarkRequest:
    """What run_benchmark benchmarks, and how.

    alfa_folder: flight folders in ALFA's processed layout; calibrate_on: another such
    folder whose flights calibrate every flight of alfa_folder (None: leave_out);
    leave_out: LEAVE_OUT, what each calibration leaves out ("flight": the screened flight;
    "day": the screened flight's day); with_peer: run keipour2019_rls on the same flights
    and folds; figures_dir: the folder of each flight's figure (None: no figures);
    json_path: the record's file (None: not written); airframe_path: the airframe file the
    flights are read with; generators: the detector's generators by name
    (detection.generators); schedule: "auto" or "none" (calibration_fit.SCHEDULES);
    false_alarm_probability: the designed one per sample and test; forgetting_factor: the
    RLS's lambda_f (0..1); window_samples: M, the GLRT window [samples]; settle_s: no test
    this long after a start [s]; campaign: where the flights are read."""

    alfa_folder: Path
    calibrate_on: Path | None
    leave_out: str
    with_peer: bool
    figures_dir: Path | None
    json_path: Path | None
    airframe_path: Path
    generators: tuple[str, ...]
    schedule: str
    false_alarm_probability: float
    forgetting_factor: float
    window_samples: int
    settle_s: float
    campaign: CampaignOptions = field(default_factory=CampaignOptions)


def alfa_paths(folder: Path) -> dict[Path, FlightTruth]:
    """The labelled ALFA flights in folder with their truth; the unlabelled said and left
    out. BadInputError for a folder without ALFA flights or a truth that cannot be read."""
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
    return {path: truth for path, truth in truths.items() if truth.labelled}


def labelled_flights(truths: dict[Path, FlightTruth], airframe_path: Path,
                     options: CampaignOptions) -> list[LabelledFlight]:
    """The flights at truths' paths, with those truths, read with the airframe file at
    airframe_path onto the detector's grid (DEFAULT_SAMPLE_PERIOD_S [s]) where options
    say."""
    replays = replays_on_grid(list(truths), airframe_path, DEFAULT_SAMPLE_PERIOD_S,
                              "ALFA flights", options)
    return [LabelledFlight(path.name, replay.inputs, truth)
            for (path, truth), replay in zip(truths.items(), replays, strict=True)]


def calibrator(request: AlfaBenchmarkRequest) -> Calibrate:
    """calibrate(fault-free parts) -> Calibration with the request's settings."""
    def calibrated(flights: Sequence[DetectorFlight]) -> Calibration:
        return calibrate_scheduled(
            flights, request.schedule, sample_period_s=DEFAULT_SAMPLE_PERIOD_S,
            forgetting_factor=request.forgetting_factor, window=request.window_samples,
            settle_s=request.settle_s, airframe=ALFA_AIRFRAME,
            generators=request.generators)[0]

    return calibrated


def folds(request: AlfaBenchmarkRequest, flights: Sequence[LabelledFlight],
          calibration_count: int) -> list[Fold]:
    """Which flights calibrate which: the other flights, the other days, or (with
    calibrate_on) all calibration_count calibration flights every flight."""
    if request.calibrate_on is not None:
        return [(list(range(len(flights))), list(range(calibration_count)))]
    if request.leave_out == "day":
        return leave_out_folds([flight_day(f.inputs.start_stamp_s) for f in flights])
    return leave_out_folds([flight.name for flight in flights])


def mode(request: AlfaBenchmarkRequest) -> str:
    """The record's `mode`: which folds."""
    return (f"leave_one_{request.leave_out}_out" if request.calibrate_on is None
            else f"calibrated_on {request.calibrate_on}")


def printed_summary(title: str, outcomes: Sequence[FlightOutcome]) -> dict[str, Any]:
    """The flights' lines, the table per kind and the summary, printed under title; the
    summary (alfa_summary)."""
    summary = alfa_summary(outcomes)
    print(f"--- {title}")
    print(OUTCOME_HEADING)
    print("\n".join(map(outcome_line, outcomes)))
    print("\n".join(kind_lines(summary)))
    print(f"within {ALFA_DETECTION_LIMIT_S:g} s (ALFA's evaluator): "
          f"{summary_line(within_counts(summary, ALFA_DETECTION_LIMIT_S))}")
    print(f"at any delay: {summary_line(summary)}")
    return summary


def peer_outcomes(request: AlfaBenchmarkRequest, truths: dict[Path, FlightTruth],
                  calibration_truths: dict[Path, FlightTruth] | None,
                  fold_list: list[Fold]) -> list[FlightOutcome]:
    """The peer's outcomes on the same flights and folds."""
    def read(flight_truths: dict[Path, FlightTruth]) -> list[peer.PeerFlight]:
        return read_in_campaign(peer.peer_flight_of, [
            peer.PeerTask.of(path, request.airframe_path, truth)
            for path, truth in flight_truths.items()], f"ALFA flights for {peer.NAME}",
            request.campaign)

    try:
        flights = read(truths)
        calibration = None if calibration_truths is None else read(calibration_truths)
    except ValueError as error:
        raise BadInputError(str(error)) from None
    return peer.screened_in_folds(flights, fold_list, calibration)


def figure_drawer(folder: Path | None, false_alarm_probability: float) -> Seen | None:
    """seen() that draws each screened flight into folder (None: no figures): its inputs,
    statistics and combined alarms, the onset and ALFA's 5 s after it."""
    if folder is None:
        return None
    folder.mkdir(parents=True, exist_ok=True)

    def draw(flight: LabelledFlight, calibration: Calibration,
             samples: list[DetectorSample]) -> None:
        channels, period_s = calibration.channel_names, calibration.sample_period_s
        onset = flight.truth.onset_stamp_s
        plot_screening(f"{flight.name}: {flight.truth.failure or 'no failure'}, designed P_FA "
                       f"{false_alarm_probability:g}", flight.inputs, samples, channels,
                       alarm_intervals(samples, channels, period_s), period_s,
                       folder / f"{flight.name}.png",
                       None if onset is None else onset - flight.inputs.start_stamp_s,
                       ALFA_DETECTION_LIMIT_S)

    return draw


def run_benchmark(request: AlfaBenchmarkRequest) -> dict[str, Any]:
    """The benchmark's record (`flights`, `summary`, `peers` and the settings:
    docs/design.md#the-alfa-benchmarks-record), printed as it goes (the project's detector,
    then the peer: a line per flight, the table per kind, the summary within ALFA's 5 s and
    at any delay), written to request.json_path unless it is None. BadInputError for a
    folder without ALFA flights, flights that cannot be read, or a generator without samples
    to fit it on; OSError for a figure or record that cannot be written."""
    started = time.monotonic()
    options = request.campaign
    truths = alfa_paths(request.alfa_folder)
    flights = labelled_flights(truths, request.airframe_path, options)
    calibration_truths = calibration_flights = None
    if request.calibrate_on is not None:
        calibration_truths = alfa_paths(request.calibrate_on)
        calibration_flights = labelled_flights(calibration_truths, request.airframe_path,
                                               options)
    fold_list = folds(request, flights, len(calibration_truths or ()))
    try:
        outcomes = screened_in_folds(flights, fold_list, calibrator(request),
                                     request.false_alarm_probability, calibration_flights,
                                     seen=figure_drawer(request.figures_dir,
                                                        request.false_alarm_probability))
    except ValueError as error:  # a generator without samples to fit it on
        raise BadInputError(str(error)) from None
    summary = printed_summary("the project's detector", outcomes)
    peers = {}
    if request.with_peer:
        peer_rows = peer_outcomes(request, truths, calibration_truths, fold_list)
        peers[peer.NAME] = {"flights": [outcome_dict(o) for o in peer_rows],
                            "summary": printed_summary(f"peer: {peer.NAME}", peer_rows)}
    record = {
        "alfa_folder": str(request.alfa_folder),
        "mode": mode(request),
        "generators": list(request.generators),
        "schedule": request.schedule,
        "false_alarm_probability": request.false_alarm_probability,
        "forgetting_factor": request.forgetting_factor,
        "window": request.window_samples,
        "settle_s": request.settle_s,
        "onset_margin_s": ONSET_MARGIN_S,
        "wall_time_s": round(time.monotonic() - started, 1),
        "flights": [outcome_dict(outcome) for outcome in outcomes],
        "summary": summary,
        "peers": peers,
    }
    if request.json_path is not None:
        request.json_path.write_text(json.dumps(record, indent=2) + "\n")
    return record
