"""Build description of ros_processes: one top-level module, for scripts/demo.py and the
tests, which both see the install space (scripts/env.sh) and nothing else in common."""

from setuptools import setup

PACKAGE = "ros_processes"

setup(
    name=PACKAGE,
    version="0.1.0",
    py_modules=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="UAV fault diagnostics maintainers",
    maintainer_email="maintainers@uav-fault-diagnostics.example.org",
    description="Start ROS nodes and tools as processes, and always stop them.",
    license="Apache-2.0",
)
