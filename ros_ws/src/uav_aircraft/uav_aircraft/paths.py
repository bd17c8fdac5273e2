"""Where the aircraft folders are: the installed ones, which the code reads, and the source
tree's, where the calibration commands write."""

from pathlib import Path

from uav_common.package_data import share_dir, source_dir

PACKAGE = "uav_aircraft"
FOLDER = "aircraft"


def aircraft_dir() -> Path:
    """The folder of the aircraft folders, one per vehicle (uav_aircraft.vehicles)."""
    return share_dir(PACKAGE) / FOLDER


def calibration_output_path(vehicle: str, file_name: str) -> Path:
    """Where a calibration command writes the vehicle's calibration file file_name by
    default: its folder in this source tree (scripts/setup.sh then installs it)."""
    return source_dir(PACKAGE) / FOLDER / vehicle / file_name
