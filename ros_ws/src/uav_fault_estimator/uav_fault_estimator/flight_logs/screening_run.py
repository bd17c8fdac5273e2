"""The two commands of scripts/screen_logs.py (its docstring is the user's account, and
docs/flight_logs.md): calibrate the self-tuning detector from fault-free logs of one
airframe (calibrate_from_logs), and screen logs of it for alarms against their ground truth
where it is known (screen). Each prints what the command prints and writes its files; input
the user must mend is a loading.BadInputError with its line. No ROS here.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from uav_fault_estimator.campaigns.campaign import CampaignOptions
from uav_fault_estimator.detection.calibration import DEFAULT_SAMPLE_PERIOD_S, Calibration
from uav_fault_estimator.detection.calibration_file import calibration_to_dict, read_calibration
from uav_fault_estimator.detection.calibration_fit import ScheduleError, calibrate_scheduled
from uav_fault_estimator.detection.detector import run_detector
from uav_fault_estimator.flight_logs.benchmark import LabelledFlight, fault_free_part
from uav_fault_estimator.flight_logs.evaluation import (
    ALFA_DETECTION_LIMIT_S,
    OUTCOME_HEADING,
    FlightOutcome,
    evaluation_summary,
    flight_outcome,
    outcome_dict,
    outcome_line,
    summary_line,
)
from uav_fault_estimator.flight_logs.loading import (
    BadInputError,
    LoadedLog,
    airframe_of,
    load_logs,
)
from uav_fault_estimator.flight_logs.screening import (
    TESTS,
    alarm_intervals,
    alarm_table,
    log_summary,
    plot_screening,
    write_alarm_csv,
)
from uav_fault_estimator.reporting.calibration_output import write_calibration


@dataclass(frozen=True)
class CalibrationRequest:
    """What calibrate_from_logs calibrates from, and how.

    log_paths: the fault-free logs (files, log folders, or folders of logs);
    airframe_path: the airframe file they are read with (its name goes into the
    calibration); out_path: the calibration file to write (None: none written);
    schedule: calibration_fit.SCHEDULES ("auto", "airspeed", "none"); generators: the
    detector's generators by name (detection.generators); truth_table_path: a truth table
    (None: only ALFA folders' own truths are known); forgetting_factor: the RLS's lambda_f
    (0..1); window_samples: M, the GLRT window [samples]; settle_s: no test this long after
    a start [s]; campaign: where the logs are read."""

    log_paths: tuple[Path, ...]
    airframe_path: Path
    out_path: Path | None
    schedule: str
    generators: tuple[str, ...]
    truth_table_path: Path | None
    forgetting_factor: float
    window_samples: int
    settle_s: float
    campaign: CampaignOptions = field(default_factory=CampaignOptions)


@dataclass(frozen=True)
class ScreeningRequest:
    """What screen screens, with what, and where its files go.

    log_paths: the logs (files, log folders, or folders of logs); calibration_path: the
    calibration file (calibrate_from_logs's, for this airframe); airframe_path: the airframe
    file the logs are read with; out_dir: the folder of the tables, figures and summaries
    (created if needed); false_alarm_probability: the designed one per sample and test
    (0..1, exclusive); truth_table_path: a truth table (None: only ALFA folders' own truths
    are known); campaign: where the logs are read."""

    log_paths: tuple[Path, ...]
    calibration_path: Path
    airframe_path: Path
    out_dir: Path
    false_alarm_probability: float
    truth_table_path: Path | None
    campaign: CampaignOptions = field(default_factory=CampaignOptions)


def calibrate_from_logs(request: CalibrationRequest) -> Calibration:
    """The calibration from the fault-free parts of request's logs (the whole of a log
    without a known truth, a failure log up to its onset less benchmark.ONSET_MARGIN_S; an
    unlabelled one left out, said), on the grid of DEFAULT_SAMPLE_PERIOD_S [s], for the
    airframe's name; written with a header naming the airframe and logs to
    request.out_path unless it is None. Prints each log's warnings, the logs left out and
    the airspeed schedule (and why none where auto found none). BadInputError for a bad
    airframe file, log or truth table, a schedule the logs cannot give, unknown generators,
    or an output that cannot be written."""
    started = time.monotonic()
    airframe = airframe_of(request.airframe_path)
    logs = load_logs(request.log_paths, airframe, DEFAULT_SAMPLE_PERIOD_S,
                     request.truth_table_path, request.campaign)
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
            flights, request.schedule, sample_period_s=DEFAULT_SAMPLE_PERIOD_S,
            forgetting_factor=request.forgetting_factor, window=request.window_samples,
            settle_s=request.settle_s, airframe=airframe.name,
            generators=request.generators)
    except ScheduleError as error:
        raise BadInputError(f"no airspeed schedule: {error}") from None
    except ValueError as error:
        raise BadInputError(str(error)) from None
    if unscheduled:
        print(f"no airspeed schedule: {unscheduled}")
    print(f"airspeed schedule: reference {calibration.reference_airspeed_mps:.2f} m/s"
          if calibration.scheduled else "airspeed schedule: none")
    if request.out_path is None:
        return calibration
    header = (f"# Written by scripts/screen_logs.py calibrate for the airframe "
              f"'{airframe.name}' ({airframe.path}) from the fault-free logs\n"
              + "".join(f"#   {log.replay.source}\n" for log in logs.values())
              + "# Valid for the sample period, forgetting factor and window below only.\n")
    try:
        write_calibration(request.out_path, header, calibration_to_dict(calibration),
                          f"{len(flights)} logs", time.monotonic() - started)
    except OSError as error:
        raise BadInputError(f"cannot write {request.out_path}: {error.strerror}") from None
    return calibration


def screen(request: ScreeningRequest) -> dict[str, Any]:
    """Every log of request screened with its calibration: per log its alarm intervals
    printed and written (NAME.alarms.csv), its figure (NAME.png, the onset marked where its
    truth is known) and its summary (NAME.json: screening.log_summary, with its outcome
    where its truth is known), and DIR/summary.json (the calibration, the settings, every
    log's summary and, with truths, the evaluation), DIR being request.out_dir; returns
    summary.json's content. Prints a line per log, its alarm table, and with truths the
    table of outcomes and its summary. BadInputError for a false-alarm probability outside
    (0, 1), a bad airframe file, log or truth table, a calibration that is malformed or for
    another airframe, or an output folder that cannot be made."""
    probability = request.false_alarm_probability
    if not 0.0 < probability < 1.0:
        raise BadInputError(f"--false-alarm-probability {probability:g}: "
                            "must lie between 0 and 1")
    airframe = airframe_of(request.airframe_path)
    try:
        calibration = read_calibration(str(request.calibration_path), airframe.name)
    except ValueError as error:
        raise BadInputError(str(error)) from None
    logs = load_logs(request.log_paths, airframe, calibration.sample_period_s,
                     request.truth_table_path, request.campaign)
    out = request.out_dir
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise BadInputError(f"cannot write into {out}: {error.strerror}") from None
    summaries, outcomes = [], []
    for name, log in logs.items():
        summary, outcome = screened_log(name, log, calibration, probability, out)
        summaries.append(summary)
        if outcome is not None:
            outcomes.append(outcome)
    evaluation = None
    if outcomes:
        evaluation = evaluation_summary(outcomes)
        print(OUTCOME_HEADING)
        print("\n".join(map(outcome_line, outcomes)))
        print(summary_line(evaluation))
    record = {
        "calibration": str(request.calibration_path),
        "airframe": airframe.name,
        "channels": list(calibration.channel_names),
        "airspeed_schedule": calibration.scheduled,
        "sample_period_s": calibration.sample_period_s,
        "false_alarm_probability": probability,
        "logs": summaries,
        "evaluation": evaluation,
    }
    (out / "summary.json").write_text(json.dumps(record, indent=2) + "\n")
    print(f"screened {len(summaries)} logs into {out}")
    return record


def screened_log(name: str, log: LoadedLog, calibration: Calibration,
                 false_alarm_probability: float, out: Path
                 ) -> tuple[dict[str, Any], FlightOutcome | None]:
    """One log screened with calibration at false_alarm_probability (per sample and test):
    its line and alarm table printed, NAME.alarms.csv, NAME.png and NAME.json written into
    out; its summary, and its outcome (None without a labelled truth)."""
    replay, truth = log
    inputs = replay.inputs
    channels, period_s = calibration.channel_names, calibration.sample_period_s
    samples = run_detector(calibration, inputs.flight, false_alarm_probability)
    if not samples:
        raise BadInputError(
            f"{name}: the calibration's generators ({', '.join(channels)}) ran on none of its "
            "samples: the log lacks a value they take (the tracking generators need the "
            "autopilot's roll and pitch setpoints); use a calibration of generators it "
            "carries (screen_logs.py calibrate --generators)")
    intervals = alarm_intervals(samples, channels, period_s)
    summary = log_summary(name, replay.source, samples, channels, period_s, inputs.warnings,
                          inputs.start_stamp_s)
    counts = summary["alarm_samples"]
    print(f"{name}: {summary['samples']} samples, {summary['tested_samples']} tested; "
          "alarm samples glrt {}, parameter {}, fast {}, combined {}; first combined alarm {}"
          .format(*(counts[test]["any"] for test in TESTS),
                  "none" if summary["first_combined_alarm_s"] is None
                  else f"at {summary['first_combined_alarm_s']:.1f} s"))
    print(alarm_table(intervals))
    onset_s = outcome = None
    if truth is not None and truth.labelled:
        outcome = flight_outcome(name, truth, samples, channels, inputs.start_stamp_s)
        summary["outcome"] = outcome_dict(outcome)
        if truth.onset_stamp_s is not None:
            onset_s = truth.onset_stamp_s - inputs.start_stamp_s
    write_alarm_csv(out / f"{name}.alarms.csv", intervals, inputs.start_stamp_s)
    plot_screening(f"{name}: designed P_FA {false_alarm_probability:g} per sample and test",
                   inputs, samples, channels, intervals, period_s, out / f"{name}.png",
                   onset_s, ALFA_DETECTION_LIMIT_S)
    (out / f"{name}.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary, outcome
