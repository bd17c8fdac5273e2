"""Build description of uav_aircraft: the aircraft folders and the modules that read them."""

from pathlib import Path

from setuptools import find_packages, setup

PACKAGE = "uav_aircraft"
HERE = Path(__file__).parent


def share_tree(folder: str) -> list[tuple[str, list[str]]]:
    """data_files entries installing every file below `folder` under share/<pkg>/<folder>."""
    entries: dict[str, list[str]] = {}
    for path in sorted((HERE / folder).rglob("*")):
        if path.is_file():
            relative = path.relative_to(HERE)
            entries.setdefault(f"share/{PACKAGE}/{relative.parent}", []).append(str(relative))
    return sorted(entries.items())


setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        *share_tree("aircraft"),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="UAV fault diagnostics maintainers",
    maintainer_email="maintainers@uav-fault-diagnostics.example.org",
    description="The aircraft the project flies and models: one folder each, and what reads it.",
    license="Apache-2.0",
)
