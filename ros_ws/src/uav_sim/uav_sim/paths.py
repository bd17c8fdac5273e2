"""Where the simulator's data lives: the Aerosonde's JSBSim files and the scenarios."""

from pathlib import Path

from uav_common.package_data import share_dir

PACKAGE = "uav_sim"


def jsbsim_root() -> Path:
    """JSBSim root folder with aircraft/, engine/ and systems/ of the Aerosonde."""
    return share_dir(PACKAGE) / "jsbsim"


def scenarios_dir() -> Path:
    """Folder of the shipped scenario files."""
    return share_dir(PACKAGE) / "scenarios"
