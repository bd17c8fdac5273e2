"""The parameter files and tables are what the nodes declare: generated, never edited."""

from __future__ import annotations

import subprocess
import sys

import pytest
import yaml
from helpers.repo import REPO_ROOT
from uav_common.package_data import default_parameters

sys.path.insert(0, str(REPO_ROOT / "tools"))
import parameter_pages


@pytest.mark.timeout(60)
def test_the_config_files_and_tables_are_up_to_date():
    result = subprocess.run([sys.executable, str(REPO_ROOT / "tools" / "parameter_pages.py"),
                             "--check"], capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr


@pytest.mark.timeout(60)
@pytest.mark.parametrize("node", parameter_pages.NODES, ids=lambda node: node.name)
def test_each_default_reads_back_with_its_type(node):
    """What the installed YAML gives (--params-file users copy it) is each declared default,
    of the declared type (4.0 a real, not 4)."""
    installed = default_parameters(node.package, f"{node.name}.yaml")
    declared = {name: spec.default for name, spec in node.specs.items()}
    assert installed == declared
    assert {name: type(value) for name, value in installed.items()} == {
        name: type(value) for name, value in declared.items()}
    generated = yaml.safe_load(parameter_pages.config_file(node))["/**"]["ros__parameters"]
    assert generated == declared
