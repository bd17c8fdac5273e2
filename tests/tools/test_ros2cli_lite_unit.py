"""Formatting and parsing of the project's `ros2` command, without a ROS graph."""

import sys
from pathlib import Path

import pytest
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))

from ros2cli_lite import CliError, field_value, format_document, parser, rate_report


@pytest.mark.timeout(10)
def test_rate_report_of_a_steady_10_hz_stream() -> None:
    report = rate_report([0.0, 0.1, 0.2, 0.3, 0.4])
    assert report.splitlines() == [
        "average rate: 10.000",
        "\tmin: 0.100s max: 0.100s std dev: 0.00000s window: 5",
    ]


@pytest.mark.timeout(10)
def test_rate_report_of_an_uneven_stream() -> None:
    report = rate_report([0.0, 0.1, 0.3])
    assert report.startswith("average rate: 6.667\n\tmin: 0.100s max: 0.200s std dev: 0.05000s")


@pytest.mark.timeout(10)
def test_message_document_keeps_field_order_and_nesting() -> None:
    from uav_fault_msgs.msg import WindEstimate

    message = WindEstimate(north_mps=4.0, east_mps=3.0, down_mps=0.0, filter_time_constant_s=10.0)
    message.header.frame_id = "ned"
    text = format_document(message)
    assert text.endswith("\n---")
    assert text.splitlines()[:4] == ["header:", "  stamp:", "    sec: 0", "    nanosec: 0"]
    assert yaml.safe_load(text[: -len("---")])["filter_time_constant_s"] == 10.0


@pytest.mark.timeout(10)
def test_field_path_errors_name_the_missing_part() -> None:
    from uav_fault_msgs.msg import FaultVector

    message = FaultVector(names=["a"], values_pct=[1.0])
    assert list(field_value(message, "values_pct")) == [1.0]
    with pytest.raises(CliError, match="no field 'sec'"):
        field_value(message, "header.sec")
    with pytest.raises(CliError, match="no field 'x'"):
        field_value(message, "names.x")


@pytest.mark.timeout(10)
def test_run_passes_ros_args_through_untouched() -> None:
    args = parser().parse_args(["run", "pkg", "exe", "--ros-args", "-p", "rate:=2.0"])
    assert (args.package, args.executable) == ("pkg", "exe")
    assert args.arguments == ["--ros-args", "-p", "rate:=2.0"]
