"""Build description of uav_common: Python modules only (no executables, no data)."""

from setuptools import find_packages, setup

PACKAGE = "uav_common"

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
    description="Contracts and ROS glue shared by the simulator and the estimator.",
    license="Apache-2.0",
)
