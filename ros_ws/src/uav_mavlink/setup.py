"""Build description of uav_mavlink: an autopilot's MAVLink link as the project's streams."""

from setuptools import find_packages, setup

PACKAGE = "uav_mavlink"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config", ["config/mavlink_node.yaml", "config/autopilot_node.yaml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="UAV fault diagnostics maintainers",
    maintainer_email="maintainers@uav-fault-diagnostics.example.org",
    description="An autopilot's MAVLink link as the project's streams.",
    license="Apache-2.0",
    entry_points={"console_scripts": ["mavlink_node = uav_mavlink.ros.mavlink_node:main",
                                      "autopilot_node = uav_mavlink.ros.autopilot_node:main",
                                      "log_streamer = uav_mavlink.log_streamer:main"]},
)
