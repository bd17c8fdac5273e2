"""Flight logs read for the flight-log commands (screening_run: scripts/screen_logs.py;
alfa_run: scripts/alfa_benchmark.py): the airframe file, the logs put on the detector's
grid as one campaign (campaigns.campaign: local workers, a Dask cluster, a cache), each with
its ground truth; and BadInputError, the input the user must mend, which both commands turn
into exit status 2 with its message. No ROS here.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NamedTuple

from uav_aircraft.airframe import Airframe, load_airframe

from uav_fault_estimator.campaigns.campaign import CampaignOptions, run_campaign
from uav_fault_estimator.flight_logs.ground_truth import (
    FlightTruth,
    flight_truth,
    read_truth_table,
)
from uav_fault_estimator.flight_logs.readers import log_paths
from uav_fault_estimator.flight_logs.replay import LogReplay, ReplayTask, replay_of


class BadInputError(Exception):
    """Input the user must mend: exit status 2 with the message as one line."""


def airframe_of(path: Path) -> Airframe:
    """The airframe file at path, or BadInputError with its line."""
    try:
        return load_airframe(path)
    except ValueError as error:  # AirframeError and the strict reader's lines
        raise BadInputError(str(error)) from None


def read_in_campaign(function: Callable[[Any], Any], tasks: Sequence[Any], what: str,
                     options: CampaignOptions) -> list[Any]:
    """function(task) of each task (a log or flight to read) over a campaign run where
    options say, in the tasks' order; what names the tasks in its progress bar ("logs").
    BadInputError (a line per task that failed) when any fails."""
    read = run_campaign(function, tasks, what, options)
    if read.failures:
        raise BadInputError("\n".join(failure.message for failure in read.failures))
    return read.results


def replays_on_grid(paths: Sequence[Path], airframe_path: Path, period_s: float, what: str,
                    options: CampaignOptions) -> list[LogReplay]:
    """The log at each of paths (a file or a log's folder) read with the airframe file at
    airframe_path and put on the grid of period_s [s] (replay.load_replay), in the order of
    paths, over a campaign (read_in_campaign: what names the logs; BadInputError)."""
    tasks = [ReplayTask.of(path, airframe_path, None, period_s) for path in paths]
    return read_in_campaign(replay_of, tasks, what, options)


class LoadedLog(NamedTuple):
    """A log on the grid and its ground truth (None: not known)."""

    replay: LogReplay
    truth: FlightTruth | None


def load_logs(paths: Sequence[Path], airframe: Airframe, period_s: float,
              truth_table: Path | None, options: CampaignOptions) -> dict[str, LoadedLog]:
    """Every log that paths name (folders expanded: readers.log_paths) on the grid of
    period_s [s], read where options say, with its truth (the truth_table file's row,
    else an ALFA folder's own: ground_truth.flight_truth), by name (the file or folder name
    without its suffix), each log's warnings printed once; BadInputError for a bad truth
    table, two logs of one name (their outputs would overwrite each other), or logs that
    cannot be read or used (a line each, once every other log is read)."""
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
    replays = replays_on_grid(list(named.values()), airframe.path, period_s, "logs", options)
    logs = {}
    for (name, path), replay in zip(named.items(), replays, strict=True):
        logs[name] = LoadedLog(replay, flight_truth(path, name, table))
        for line in replay.inputs.warnings:  # each names its log
            print(line)
    return logs
