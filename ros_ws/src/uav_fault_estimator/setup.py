"""Build description of uav_fault_estimator: Python modules and node configuration."""

from pathlib import Path

from setuptools import find_packages, setup

PACKAGE = "uav_fault_estimator"
HERE = Path(__file__).parent

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        # the nodes' parameter YAML, and the Foxglove layout (JSON)
        *[(f"share/{PACKAGE}/{folder}",
           [str(path.relative_to(HERE)) for path in sorted((HERE / folder).glob("*.*"))
            if path.suffix in (".yaml", ".json")])
          for folder in ("config",)],
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="UAV fault diagnostics maintainers",
    maintainer_email="maintainers@uav-fault-diagnostics.example.org",
    description="Residuals, fault sensitivities, MHE fault estimation and detection for the UAV.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            f"residual_node = {PACKAGE}.nodes.residual_node:main",
            f"mhe_node = {PACKAGE}.nodes.mhe_node:main",
            f"recorder_node = {PACKAGE}.nodes.recorder_node:main",
            f"detector_node = {PACKAGE}.nodes.detector_node:main",
            f"foxglove_node = {PACKAGE}.nodes.foxglove_node:main",
            f"log_replay_node = {PACKAGE}.nodes.log_replay_node:main",
            f"standard_topics_node = {PACKAGE}.nodes.standard_topics_node:main",
        ],
    },
)
