"""Each ROS package's package.xml names every package its code imports: a
rosdep key per import, or, for the few with none, a mention in the manifest's comment."""

from __future__ import annotations

import ast
import re
import sys
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import pytest

SOURCE = Path(__file__).resolve().parent.parent / "ros_ws" / "src"
# import name -> rosdep key, where they differ
ROSDEP_KEYS = {"numpy": "python3-numpy", "yaml": "python3-yaml", "scipy": "python3-scipy",
               "matplotlib": "python3-matplotlib", "cryptography": "python3-cryptography"}


def imported(package: str) -> set[str]:
    """Top-level names of what the package's modules import, its own and the standard
    library's left out."""
    names: set[str] = set()
    for path in (SOURCE / package / package).rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names.update(alias.name.split(".")[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split(".")[0])
    return names - set(sys.stdlib_module_names) - {package, "__future__"}


@pytest.mark.timeout(30)
@pytest.mark.parametrize("package", ["uav_common", "uav_aircraft", "uav_sim",
                                     "uav_fault_estimator", "uav_mavlink", "ros2cli_lite"])
def test_every_import_is_a_declared_dependency(package):
    manifest = (SOURCE / package / "package.xml").read_text()
    root = ElementTree.fromstring(manifest)
    declared = {element.text for element in root.iter("exec_depend")}
    comments = " ".join(re.findall(r"<!--(.*?)-->", manifest, re.S))  # the pip-only ones
    missing = [name for name in sorted(imported(package))
               if ROSDEP_KEYS.get(name, name) not in declared and name not in comments]
    print(f"{package}: imports {sorted(imported(package))}")
    assert imported(package) and missing == []
