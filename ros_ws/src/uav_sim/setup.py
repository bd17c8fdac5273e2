"""Build description of uav_sim: Python modules, scenarios, config."""

from pathlib import Path

from setuptools import find_packages, setup

PACKAGE = "uav_sim"
HERE = Path(__file__).parent


setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        # the shipped scenarios and sim_node's parameter YAML (flat folders)
        *[(f"share/{PACKAGE}/{folder}",
           [str(path.relative_to(HERE)) for path in sorted((HERE / folder).glob("*.yaml"))])
          for folder in ("scenarios", "config")],
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="UAV fault diagnostics maintainers",
    maintainer_email="maintainers@uav-fault-diagnostics.example.org",
    description="Fixed-wing UAV flight simulation on JSBSim with seeded faults.",
    license="Apache-2.0",
    entry_points={"console_scripts": [f"sim_node = {PACKAGE}.ros.sim_node:main"]},
)
