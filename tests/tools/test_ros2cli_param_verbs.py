"""The `ros2` stand-in's param verbs against a live mhe_node, outputs checked line by line."""

from __future__ import annotations

import re

import pytest
import yaml
from helpers.repo import REPO_ROOT
from helpers.ros2_cli import run_cli

pytestmark = pytest.mark.integration

MHE_CONFIG = REPO_ROOT / "ros_ws/src/uav_fault_estimator/config/mhe_node.yaml"


def mhe_defaults() -> dict:
    return yaml.safe_load(MHE_CONFIG.read_text())["/**"]["ros__parameters"]


# ------------------------------------------------------------------------------ param
@pytest.mark.slow
@pytest.mark.timeout(90)
def test_param_list_get_dump_show_the_config_values(mhe_node) -> None:
    defaults = mhe_defaults()
    listing = run_cli("param", "list", "/mhe_node")
    assert listing.returncode == 0, listing.stderr
    lines = listing.stdout.splitlines()
    assert lines == sorted(lines) and all(line.startswith("  ") for line in lines)
    names = [line.strip() for line in lines]
    assert set(defaults) | {"use_sim_time"} <= set(names), names

    everyone = run_cli("param", "list")
    assert "/mhe_node:" in everyone.stdout.splitlines()

    typed = run_cli("param", "list", "mhe_node", "--param-type")
    assert "  horizon (type: integer)" in typed.stdout.splitlines()
    assert "  fault_names (type: string array)" in typed.stdout.splitlines()

    expected_lines = {
        "horizon": f"Integer value is: {defaults['horizon']}",
        "noise_variance_factor": f"Double value is: {defaults['noise_variance_factor']}",
        "arrival_centre": f"String value is: {defaults['arrival_centre']}",
        "estimate_wind_errors": f"Boolean value is: {defaults['estimate_wind_errors']}",
        "fault_names": f"String values are: {defaults['fault_names']}",
        "prior_pct": f"Double values are: array('d', {defaults['prior_pct']})",
    }
    for name, line in expected_lines.items():
        got = run_cli("param", "get", "/mhe_node", name)
        assert (got.returncode, got.stdout) == (0, line + "\n"), (name, got.stdout, got.stderr)

    dump = run_cli("param", "dump", "/mhe_node")
    assert dump.returncode == 0, dump.stderr
    assert dump.stdout.startswith("/mhe_node:\n  ros__parameters:\n")
    dumped = yaml.safe_load(dump.stdout)["/mhe_node"]["ros__parameters"]
    for name, value in defaults.items():
        assert dumped[name] == value, name
    assert dumped["use_sim_time"] is False


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_param_set_prints_the_nodes_answer_in_ros2cli_words(mhe_node) -> None:
    result = run_cli("param", "set", "/mhe_node", "horizon", "60")
    assert result.returncode == 0, result.stderr
    answer = (result.stdout + result.stderr).strip()
    # the horizon shapes the QP, built at start: read-only, so a set is refused with the reason
    assert result.stdout == ""
    assert answer == "Setting parameter failed: Trying to set a read-only parameter: horizon."
    got = run_cli("param", "get", "/mhe_node", "horizon")
    assert got.stdout == "Integer value is: 50\n"
    wrong = run_cli("param", "set", "/mhe_node", "horizon", "many")
    assert wrong.returncode == 0 and wrong.stdout == ""
    assert re.fullmatch(r"Setting parameter failed: \S.*\n", wrong.stderr), wrong.stderr
    print("param set answers:", answer, "|", wrong.stderr.strip())


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_param_errors_are_ros2cli_lines(mhe_node) -> None:
    missing_node = run_cli("param", "get", "/no_such_node", "horizon", "--spin-time", "1")
    assert (missing_node.returncode, missing_node.stderr) == (1, "Node not found\n")
    missing_param = run_cli("param", "get", "/mhe_node", "no_such_parameter")
    assert missing_param.returncode == 1 and "Traceback" not in missing_param.stderr
    assert missing_param.stderr == "Parameter not set\n" or missing_param.stdout == (
        "Parameter not set.\n"
    )
