"""Where a package's data lives: the installed share directory, or the source tree; and
what a node's installed parameter file holds (no rclpy here)."""

from pathlib import Path
from typing import Any

import yaml


def source_dir(package: str) -> Path:
    """The package's folder in this source tree (ros_ws/src/<package>), whether this module
    runs from the source tree or from the workspace's install space (a copy of it under
    ros_ws/install)."""
    here = Path(__file__).resolve()
    workspace = next((folder for folder in here.parents
                      if (folder / "src" / "uav_common").is_dir()), here.parents[2].parent)
    return workspace / "src" / package


def share_dir(package: str) -> Path:
    """The package's share folder (config/; uav_sim's scenarios/, uav_aircraft's aircraft/).

    The colcon install space when the package is installed (ament index), else its folder
    in the source tree, so that the core runs from a checkout without a build.
    """
    try:
        from ament_index_python.packages import (
            PackageNotFoundError,
            get_package_share_directory,
        )
    except ImportError:
        return source_dir(package)
    try:
        return Path(get_package_share_directory(package))
    except (PackageNotFoundError, OSError):  # not installed, or no ROS environment
        return source_dir(package)


def config_path(package: str, config_file: str) -> Path:
    """share/<package>/config/<config_file> (the installed package's when installed: run
    scripts/setup.sh after editing a config)."""
    return share_dir(package) / "config" / config_file


def default_parameters(package: str, config_file: str) -> dict[str, Any]:
    """The `/**: ros__parameters` mapping of the package's config/<config_file>."""
    with open(config_path(package, config_file)) as stream:
        return yaml.safe_load(stream)["/**"]["ros__parameters"]
