"""One entry for every flight-log format: read_log chooses the reader by what the path is."""

from __future__ import annotations

from pathlib import Path

from uav_fault_estimator.flight_logs.axes import checked_axes
from uav_fault_estimator.flight_logs.bags import read_bag
from uav_fault_estimator.flight_logs.csv_logs import read_csv_folder
from uav_fault_estimator.flight_logs.streams import FlightLog
from uav_fault_estimator.flight_logs.ulog import read_ulog


def read_log(path: Path, axes: str | None = None) -> FlightLog:
    """The flight in a log: a PX4 ULog (.ulg), a ROS 1 bag (.bag), a ROS 2 bag (a folder with
    metadata.yaml) or a folder of per-topic CSV files, with the default topics of each.
    axes ("FRD" or "FLU") overrides the format's own convention, for logs whose convention
    differs. ValueError (one line naming the path) for anything else."""
    path = Path(path)
    if axes is not None:
        checked_axes(axes)
    if path.is_file() and path.suffix == ".ulg":
        return read_ulog(path, axes or "FRD")
    if path.is_file() and path.suffix == ".bag":
        return read_bag(path, axes=axes)
    if path.is_dir() and (path / "metadata.yaml").is_file():
        return read_bag(path, axes=axes)
    if path.is_dir() and any(path.glob("*.csv")):
        return read_csv_folder(path, axes=axes)
    raise ValueError(f"{path}: not a flight log (expected a PX4 .ulg, a ROS 1 .bag, a ROS 2 "
                     "bag folder with metadata.yaml or a folder of per-topic CSV files)"
                     if path.exists() else f"{path}: no such file or folder")
