"""The `ros2` stand-in's param verbs against a live mhe_node, outputs checked line by line."""

from __future__ import annotations

import re
from collections.abc import Iterator

import pytest
import yaml
from helpers.repo import REPO_ROOT
from helpers.ros2_cli import run_cli, run_cli_all

pytestmark = pytest.mark.integration

MHE_CONFIG = REPO_ROOT / "ros_ws/src/uav_fault_estimator/config/mhe_node.yaml"


def mhe_defaults() -> dict:
    return yaml.safe_load(MHE_CONFIG.read_text())["/**"]["ros__parameters"]


@pytest.fixture
def mhe_defaults_restored(mhe_node) -> Iterator[None]:
    """For a test that sets parameters of the module's shared mhe_node: its configured
    values put back afterwards, so that the other tests see them whatever ran before."""
    yield
    restored = run_cli("param", "load", "/mhe_node", str(MHE_CONFIG), "--use-wildcard")
    assert restored.returncode == 0, restored.stderr


# ------------------------------------------------------------------------------ param
@pytest.mark.slow
@pytest.mark.timeout(90)
def test_param_list_get_dump_show_the_config_values(mhe_node) -> None:
    defaults = mhe_defaults()
    expected_lines = {
        "horizon": f"Integer value is: {defaults['horizon']}",
        "noise_variance_factor": f"Double value is: {defaults['noise_variance_factor']}",
        "arrival_centre": f"String value is: {defaults['arrival_centre']}",
        "estimate_wind_errors": f"Boolean value is: {defaults['estimate_wind_errors']}",
        "fault_names": f"String values are: {defaults['fault_names']}",
        "prior_pct": f"Double values are: array('d', {defaults['prior_pct']})",
    }
    listing, everyone, typed, dump, *gets = run_cli_all(
        ["param", "list", "/mhe_node"], ["param", "list"],
        ["param", "list", "mhe_node", "--param-type"], ["param", "dump", "/mhe_node"],
        *[["param", "get", "/mhe_node", name] for name in expected_lines],
    )
    assert listing.returncode == 0, listing.stderr
    lines = listing.stdout.splitlines()
    assert lines == sorted(lines) and all(line.startswith("  ") for line in lines)
    names = [line.strip() for line in lines]
    assert set(defaults) | {"use_sim_time"} <= set(names), names

    assert "/mhe_node:" in everyone.stdout.splitlines()

    assert "  horizon (type: integer)" in typed.stdout.splitlines()
    assert "  fault_names (type: string array)" in typed.stdout.splitlines()

    for (name, line), got in zip(expected_lines.items(), gets, strict=True):
        assert (got.returncode, got.stdout) == (0, line + "\n"), (name, got.stdout, got.stderr)

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
    # after the refusal: the value unchanged, and a value of the wrong type refused too
    got, wrong = run_cli_all(["param", "get", "/mhe_node", "horizon"],
                             ["param", "set", "/mhe_node", "horizon", "many"])
    assert got.stdout == "Integer value is: 50\n"
    assert wrong.returncode == 0 and wrong.stdout == ""
    assert re.fullmatch(r"Setting parameter failed: \S.*\n", wrong.stderr), wrong.stderr
    print("param set answers:", answer, "|", wrong.stderr.strip())


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_param_errors_are_ros2cli_lines(mhe_node) -> None:
    missing_node, missing_param = run_cli_all(
        ["param", "get", "/no_such_node", "horizon", "--spin-time", "1"],
        ["param", "get", "/mhe_node", "no_such_parameter"],
    )
    assert (missing_node.returncode, missing_node.stderr) == (1, "Node not found\n")
    assert missing_param.returncode == 1 and "Traceback" not in missing_param.stderr
    assert missing_param.stderr == "Parameter not set\n" or missing_param.stdout == (
        "Parameter not set.\n"
    )


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_param_get_and_set_of_several_names(mhe_node, mhe_defaults_restored) -> None:
    defaults = mhe_defaults()
    got, hidden, odd = run_cli_all(
        ["param", "get", "/mhe_node", "horizon", "arrival_centre"],
        ["param", "get", "/mhe_node", "horizon", "use_sim_time", "--hide-type"],
        ["param", "set", "/mhe_node", "horizon"],  # refused before it reaches the node
    )
    assert (got.returncode, got.stdout) == (0, (
        f"horizon: Integer value is: {defaults['horizon']}\n"
        f"arrival_centre: String value is: {defaults['arrival_centre']}\n"
    )), got.stderr
    assert hidden.stdout == f"horizon: {defaults['horizon']}\nuse_sim_time: False\n"
    both = run_cli("param", "set", "/mhe_node", "noise_variance_factor", "2.5", "horizon", "7")
    assert both.returncode == 0
    assert both.stdout == "noise_variance_factor: Set parameter successful\n"
    assert both.stderr == (
        "horizon: Setting parameter failed: Trying to set a read-only parameter: horizon.\n"
    )
    after = run_cli("param", "get", "/mhe_node", "noise_variance_factor")
    assert after.stdout == "Double value is: 2.5\n"
    assert (odd.returncode, odd.stderr) == (1, "Parameters must be provided as name/value "
                                               "pairs: name value [name value ...]. Got 1 "
                                               "argument(s).\n")


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_param_describe_prints_type_description_and_constraints(mhe_node) -> None:
    result = run_cli("param", "describe", "/mhe_node", "horizon", "use_sim_time")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    second = lines.index("Parameter name: use_sim_time")
    horizon, sim_time = lines[:second], lines[second:]
    assert horizon[:2] == ["Parameter name: horizon", "  Type: integer"]
    assert horizon[2].startswith("  Description: ") and len(horizon[2]) > len("  Description: ")
    assert horizon[3:5] == ["  Constraints:", "    Read only: true"]
    assert re.fullmatch(r"    Min value: \d+", horizon[5])
    assert re.fullmatch(r"    Max value: \d+", horizon[6])
    assert sim_time == ["Parameter name: use_sim_time", "  Type: boolean", "  Constraints:"]


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_param_load_sets_each_parameter_and_reports_it(mhe_node, mhe_defaults_restored,
                                                       tmp_path) -> None:
    parameters = tmp_path / "mhe.yaml"
    parameters.write_text(yaml.safe_dump(
        {"/mhe_node": {"ros__parameters": {"noise_variance_factor": 3.5, "horizon": 10}}}
    ))
    result = run_cli("param", "load", "/mhe_node", str(parameters))
    assert result.returncode == 0
    assert result.stdout == "Set parameter noise_variance_factor successful\n"
    assert result.stderr == (
        "Set parameter horizon failed: Trying to set a read-only parameter: horizon.\n"
    )
    # the project's file holds only '/**' parameters: ros2param needs --use-wildcard for
    # them; without it nothing is set, so it may run beside the read of the loaded value
    after, shared, missing = run_cli_all(
        ["param", "get", "/mhe_node", "noise_variance_factor"],
        ["param", "load", "/mhe_node", str(MHE_CONFIG)],
        ["param", "load", "/mhe_node", str(tmp_path / "none.yaml")],
    )
    assert after.stdout == "Double value is: 3.5\n"
    assert (shared.returncode, shared.stderr) == (
        1, "Param file does not contain selected parameters\n"
    )
    assert missing.returncode == 1 and len(missing.stderr.splitlines()) == 1
    wildcard = run_cli("param", "load", "/mhe_node", str(MHE_CONFIG), "--use-wildcard")
    assert wildcard.returncode == 0 and "Traceback" not in wildcard.stderr
    assert "Set parameter noise_variance_factor successful" in wildcard.stdout.splitlines()
