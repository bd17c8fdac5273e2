"""What failed in a flight and when: the ground truth a screening is evaluated against.

Two sources, one record (FlightTruth):
- a truth table, CSV with the header `log,failure,onset_stamp_s`: the log's name (its file or
  folder name without suffix, as screen_logs.py names it), the failure kind (FAILURE_KINDS,
  empty for a flight without failure) and its onset in the log's own clock [s] (UNIX time
  for ROS logs; empty without failure);
- ALFA's flight folders: a `<folder>-failure_status-<part>.csv` per failed part, whose first
  `%time` [ns] is the onset; a folder without one had no failure, and a folder whose name
  says `no_ground_truth` is unlabelled (ALFA's own word): no truth.
No ROS here.
"""

from __future__ import annotations

import csv
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from uav_fault_estimator.detection.generators import FAILURE_GENERATORS
from uav_fault_estimator.flight_logs.csv_logs import csv_files

# The failures ALFA injects (their channels: detection.generators.FAILURE_GENERATORS).
FAILURE_KINDS = tuple(FAILURE_GENERATORS)
# ALFA's failure_status topics by the part they name (`engines` for the engine).
_ALFA_PARTS = {"failure_status_engines": "engine", "failure_status_aileron": "aileron",
               "failure_status_elevator": "elevator", "failure_status_rudder": "rudder"}
UNLABELLED_MARK = "no_ground_truth"
TRUTH_COLUMNS = ("log", "failure", "onset_stamp_s")


@dataclass(frozen=True)
class FlightTruth:
    """failure: the kind (FAILURE_KINDS; several joined by '+', first onset first) or None
    for a flight without failure; onset_stamp_s: its onset in the log's clock [s] or None;
    labelled: False for a flight whose truth nobody recorded (neither a calibration nor an
    evaluation may use it)."""

    failure: str | None
    onset_stamp_s: float | None
    labelled: bool = True

    @property
    def expected_channels(self) -> tuple[str, ...]:
        """The channels that see this failure (none without one)."""
        return tuple(channel for kind in (self.failure or "").split("+") if kind
                     for channel in FAILURE_GENERATORS[kind])


NO_FAILURE = FlightTruth(None, None)
UNLABELLED = FlightTruth(None, None, labelled=False)


def alfa_truth(folder: Path) -> FlightTruth:
    """The truth of an ALFA flight folder from its failure_status files (UNLABELLED for one
    named so). ValueError (one line naming the file) for a file without a time."""
    folder = Path(folder)
    if UNLABELLED_MARK in folder.name:
        return UNLABELLED
    onsets = {}
    for key, path in csv_files(folder).items():
        if key in _ALFA_PARTS:
            with path.open(newline="") as file:
                rows = csv.DictReader(file)
                first = next(rows, None)
            if first is None or not first.get("%time", "").strip().isdigit():
                raise ValueError(f"{path}: no %time [ns] in its first row")
            onsets[_ALFA_PARTS[key]] = int(first["%time"]) * 1e-9
    if not onsets:
        return NO_FAILURE
    kinds = sorted(onsets, key=lambda kind: (onsets[kind], kind))
    return FlightTruth("+".join(kinds), onsets[kinds[0]])


def read_truth_table(path: Path) -> dict[str, FlightTruth]:
    """A truth table (TRUTH_COLUMNS) by log name; ValueError (one line naming the file and
    row) for a bad header, an unknown kind, an onset that is not a number, or a log twice."""
    path = Path(path)
    try:
        with path.open(newline="") as file:
            rows = list(csv.reader(file))
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise ValueError(f"truth table {path}: cannot be read ({error})") from None
    if not rows or tuple(cell.strip() for cell in rows[0]) != TRUTH_COLUMNS:
        raise ValueError(f"truth table {path}: the header must be {','.join(TRUTH_COLUMNS)}")
    table: dict[str, FlightTruth] = {}
    for number, row in enumerate(rows[1:], start=2):
        table.update([_truth_row(path, number, row, table)])
    return table


def _truth_row(path: Path, number: int, row: list[str],
               table: Mapping[str, FlightTruth]) -> tuple[str, FlightTruth]:
    """One row of a truth table as (log, truth); ValueError naming the row."""
    where = f"truth table {path}, row {number}"
    if len(row) != len(TRUTH_COLUMNS):
        raise ValueError(f"{where}: {len(row)} cells, expected {len(TRUTH_COLUMNS)}")
    log, failure, onset = (cell.strip() for cell in row)
    if log in table:
        raise ValueError(f"{where}: log {log} a second time")
    if not failure:
        if onset:
            raise ValueError(f"{where}: an onset without a failure")
        return log, NO_FAILURE
    unknown = [kind for kind in failure.split("+") if kind not in FAILURE_GENERATORS]
    if unknown:
        raise ValueError(f"{where}: failure {unknown[0]!r} is not one of "
                         f"{', '.join(FAILURE_KINDS)} (join several with +)")
    try:
        onset_stamp_s = float(onset)
    except ValueError:
        raise ValueError(f"{where}: onset {onset!r} is not a time in seconds") from None
    return log, FlightTruth(failure, onset_stamp_s)


def is_alfa_flight(folder: Path) -> bool:
    """Whether a log is an ALFA flight folder (its files named FOLDER-<topic>.csv)."""
    folder = Path(folder)
    return folder.is_dir() and any(
        path.stem.startswith(f"{folder.name}-") for path in folder.glob("*.csv"))



def flight_truth(path: Path, name: str,
                 table: Mapping[str, FlightTruth] | None) -> FlightTruth | None:
    """A log's truth: its row of the table when one is given (None when it has none), else
    an ALFA flight folder's own (alfa_truth), else None (not known)."""
    if table is not None:
        return table.get(name)
    return alfa_truth(path) if is_alfa_flight(path) else None
