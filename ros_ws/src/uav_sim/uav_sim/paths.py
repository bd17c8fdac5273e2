"""Where the simulator's data lives: the scenarios."""

from pathlib import Path

from uav_common.package_data import share_dir

PACKAGE = "uav_sim"


def scenarios_dir() -> Path:
    """Folder of the shipped scenario files."""
    return share_dir(PACKAGE) / "scenarios"
