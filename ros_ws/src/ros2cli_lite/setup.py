"""Build description of ros2cli_lite: the `ros2` command, installed into the workspace's bin/."""

from setuptools import find_packages, setup

PACKAGE = "ros2cli_lite"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="UAV fault diagnostics maintainers",
    maintainer_email="maintainers@uav-fault-diagnostics.example.org",
    description="A small ros2 command for machines without ros2cli.",
    license="Apache-2.0",
    # no setup.cfg script folder: `ros2` goes to install/ros2cli_lite/bin, which colcon's
    # setup scripts put on PATH
    entry_points={"console_scripts": [f"ros2 = {PACKAGE}.cli:main"]},
)
