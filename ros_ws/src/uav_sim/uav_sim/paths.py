"""Where the simulator's data lives: the aircraft folders and the scenarios."""

from pathlib import Path

from uav_common.package_data import share_dir

PACKAGE = "uav_sim"


def aircraft_dir() -> Path:
    """The folder of the aircraft folders, one per vehicle (uav_sim.vehicles)."""
    return share_dir(PACKAGE) / "aircraft"


def scenarios_dir() -> Path:
    """Folder of the shipped scenario files."""
    return share_dir(PACKAGE) / "scenarios"
