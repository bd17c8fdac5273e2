"""The `ros2` stand-in's interface show/list/package and pkg executables on the installed
packages, and `ros2 run --prefix` starting a live node."""

from __future__ import annotations

import pytest
from helpers.ros2_cli import run_cli, run_cli_all
from uav_common.ros_processes import ros2_run_argv

ALARM_FIELDS = [
    "string[] channel_names", "float64[] statistic", "float64[] threshold", "bool[] alarm",
    "float64[] parameter_deviation", "float64 parameter_threshold", "bool parameter_alarm",
    "float64[] fast_statistic", "float64[] fast_threshold", "bool[] fast_alarm",
    "string[] template_kinds", "float64[] template_statistic", "float64[] template_threshold",
    "bool[] template_alarm", "bool combined_alarm", "float64 false_alarm_probability",
    "float64 fast_false_alarms_per_hour", "float64 template_false_alarms_per_hour",
    "string cause",
]
HEADER = ["std_msgs/Header header", "\tbuiltin_interfaces/Time stamp", "\t\tint32 sec",
          "\t\tuint32 nanosec", "\tstring frame_id"]


@pytest.mark.timeout(30)
def test_interface_show_short_name_and_no_comments() -> None:
    wrong_names = {
        "uav_fault_msgs/NoSuchType": "Could not find the interface 'uav_fault_msgs/NoSuchType'",
        "a/b/c/d": "Invalid name 'a/b/c/d'. Expected three parts separated by '/'",
    }
    bare, full, short, service, *wrongs = run_cli_all(
        ["interface", "show", "uav_fault_msgs/FaultAlarm", "--no-comments"],
        ["interface", "show", "uav_fault_msgs/msg/FaultAlarm"],
        ["interface", "show", "uav_fault_msgs/FaultAlarm"],
        ["interface", "show", "rcl_interfaces/GetParameters", "--no-comments"],
        *[["interface", "show", name] for name in wrong_names],
    )
    assert (bare.returncode, bare.stderr) == (0, "")
    assert bare.stdout.splitlines() == HEADER + ALARM_FIELDS
    assert full.stdout == short.stdout
    assert full.stdout.startswith("# ") and "" in full.stdout.splitlines()
    lines = service.stdout.splitlines()
    assert lines[:3] == ["string[] names", "---", "ParameterValue[] values"]
    assert lines[3] == "\tuint8 type" and not any("#" in line for line in lines)
    for message, wrong in zip(wrong_names.values(), wrongs, strict=True):
        assert (wrong.returncode, wrong.stderr) == (1, message + "\n")


@pytest.mark.timeout(30)
def test_interface_list_and_package() -> None:
    everything, only_services, in_package, unknown = run_cli_all(
        ["interface", "list"], ["interface", "list", "-s"],
        ["interface", "package", "uav_fault_msgs"], ["interface", "package", "no_such_package"],
    )
    assert everything.returncode == 0, everything.stderr
    lines = everything.stdout.splitlines()
    sections = [lines.index(title) for title in ("Messages:", "Services:", "Actions:")]
    assert sections == sorted(sections) and sections[0] == 0
    assert "    uav_fault_msgs/msg/FaultAlarm" in lines[: sections[1]]
    assert "    rcl_interfaces/srv/GetParameters" in lines[sections[1] : sections[2]]
    services = only_services.stdout.splitlines()
    assert services == lines[sections[1] : sections[2]]
    package = in_package.stdout.splitlines()
    assert "uav_fault_msgs/msg/FaultAlarm" in package and package == sorted(package)
    assert package == [line.strip() for line in lines if line.startswith("    uav_fault_msgs/")]
    assert (unknown.returncode, unknown.stderr) == (1, "Unknown package 'no_such_package'\n")


@pytest.mark.timeout(30)
def test_pkg_executables() -> None:
    result, full_paths, all_packages, unknown = run_cli_all(
        ["pkg", "executables", "uav_fault_estimator"],
        ["pkg", "executables", "uav_sim", "--full-path"], ["pkg", "executables"],
        ["pkg", "executables", "no_such_package"],
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert "uav_fault_estimator mhe_node" in lines and lines == sorted(lines)
    paths = full_paths.stdout.splitlines()
    assert any(path.endswith("/lib/uav_sim/sim_node") for path in paths)
    every = all_packages.stdout.splitlines()
    assert set(lines) <= set(every)
    assert (unknown.returncode, unknown.stderr) == (1, "Package 'no_such_package' not found\n")


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_run_prefix_starts_the_node_through_the_command(start_process, ros_graph,
                                                        tmp_path) -> None:
    marker = tmp_path / "prefix_ran"
    argv = ros2_run_argv("uav_fault_estimator", "mhe_node")
    node = start_process([*argv[:2], "--prefix", f"sh -c 'touch {marker}; exec \"$@\"' sh",
                          *argv[2:]], "mhe_prefixed")
    assert ros_graph.wait_for_topics(["/faults/estimate"], timeout_s=30), node.output()
    assert marker.exists() and node.running()
    missing = run_cli("run", "--prefix", "no_such_command -x", "uav_sim", "sim_node")
    assert (missing.returncode, missing.stderr) == (
        1, "Could not run 'no_such_command': No such file or directory\n"
    )
