"""Where the package's data lives: the installed share directory, or the source tree;
and the nodes' parameter defaults (no rclpy here)."""

from pathlib import Path
from typing import Any

import yaml

PACKAGE = "uav_sim"
_SOURCE_ROOT = Path(__file__).resolve().parent.parent


def share_dir() -> Path:
    """The folder holding jsbsim/, scenarios/ and config/.

    The colcon install space when the package is installed (ament index), else the
    source tree, so that the core runs from a checkout without a build.
    """
    try:
        from ament_index_python.packages import (
            PackageNotFoundError,
            get_package_share_directory,
        )
    except ImportError:
        return _SOURCE_ROOT
    try:
        return Path(get_package_share_directory(PACKAGE))
    except (PackageNotFoundError, OSError):  # not installed, or no ROS environment
        return _SOURCE_ROOT


def jsbsim_root() -> Path:
    """JSBSim root folder with aircraft/, engine/ and systems/ of the Aerosonde."""
    return share_dir() / "jsbsim"


def scenarios_dir() -> Path:
    """Folder of the shipped scenario files."""
    return share_dir() / "scenarios"


def default_parameters(package: str, config_file: str) -> dict[str, Any]:
    """The `/**: ros__parameters` mapping of share/<package>/config/<config_file> (the
    installed package's: run scripts/setup.sh after editing a config)."""
    from ament_index_python.packages import get_package_share_directory

    path = Path(get_package_share_directory(package)) / "config" / config_file
    with open(path) as stream:
        return yaml.safe_load(stream)["/**"]["ros__parameters"]
