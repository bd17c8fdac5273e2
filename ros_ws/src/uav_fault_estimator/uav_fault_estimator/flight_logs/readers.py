"""One entry for every flight-log format: read_log chooses the reader by what the path is;
log_paths finds the logs in folders by the same rule."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from uav_fault_estimator.flight_logs.axes import checked_axes
from uav_fault_estimator.flight_logs.bags import read_bag
from uav_fault_estimator.flight_logs.csv_logs import read_csv_folder
from uav_fault_estimator.flight_logs.streams import FlightLog, without_dead_airspeed
from uav_fault_estimator.flight_logs.ulog import read_ulog

# What read_log takes, in words, for the lines that refuse anything else.
LOG_KINDS = ("a PX4 .ulg, a ROS 1 .bag, a ROS 2 bag folder with metadata.yaml or a folder of "
             "per-topic CSV files")


def log_format(path: Path) -> str | None:
    """The format of the log at path by what the path is: "ulog" (a .ulg file), "ros1_bag"
    (a .bag file), "ros2_bag" (a folder with metadata.yaml), "csv" (a folder with .csv
    files); None for anything else."""
    if path.is_file():
        return {".ulg": "ulog", ".bag": "ros1_bag"}.get(path.suffix)
    if path.is_dir() and (path / "metadata.yaml").is_file():
        return "ros2_bag"
    if path.is_dir() and any(path.glob("*.csv")):
        return "csv"
    return None


def read_log(path: Path, axes: str | None = None) -> FlightLog:
    """The flight in a log: a PX4 ULog (.ulg), a ROS 1 bag (.bag), a ROS 2 bag (a folder with
    metadata.yaml) or a folder of per-topic CSV files, with the default topics of each.
    axes ("FRD" or "FLU") overrides the format's own convention, for logs whose convention
    differs. An airspeed that is 0 throughout is none (streams.without_dead_airspeed).
    ValueError (one line naming the path) for anything else."""
    path = Path(path)
    if axes is not None:
        checked_axes(axes)
    kind = log_format(path)
    if kind == "ulog":
        return without_dead_airspeed(read_ulog(path, axes or "FRD"))
    if kind in ("ros1_bag", "ros2_bag"):
        return without_dead_airspeed(read_bag(path, axes=axes))
    if kind == "csv":
        return without_dead_airspeed(read_csv_folder(path, axes=axes))
    raise ValueError(f"{path}: not a flight log (expected {LOG_KINDS})"
                     if path.exists() else f"{path}: no such file or folder")


def log_paths(paths: Iterable[Path]) -> list[Path]:
    """The logs that paths name: a path that is a log (log_format) stays; any other folder
    stands for the logs directly in it, in name order (one level: a PX4 SD card's log/
    folder holds one folder per day, each given on its own). Anything else stays too, for
    read_log to refuse with its line. ValueError (one line) for a folder without logs."""
    found = []
    for path in map(Path, paths):
        if log_format(path) is not None or not path.is_dir():
            found.append(path)
            continue
        inside = sorted(entry for entry in path.iterdir() if log_format(entry) is not None)
        if not inside:
            raise ValueError(f"{path}: no flight log in this folder (expected {LOG_KINDS})")
        found += inside
    return found
