"""Formatting and parsing of the project's `ros2` command, without a ROS graph."""

import pytest
import yaml
from ros2cli_lite.cli import CliError, field_value, format_document, parser
from ros2cli_lite.interface import interface_lines, without_comment
from ros2cli_lite.param import dump_text, get_line
from ros2cli_lite.render import (
    BandwidthWindow,
    RateWindow,
    format_bag_info,
    format_csv,
    format_size,
    set_message_fields,
    to_plain,
)

SECOND_NS = 1_000_000_000


def reports(window: RateWindow, arrivals_s: list[float]) -> list[str]:
    printed = []
    for arrival in arrivals_s:
        window.add(round(arrival * SECOND_NS))
        if (report := window.report()) is not None:
            printed.append(report)
    return printed


@pytest.mark.timeout(10)
def test_rate_window_reports_a_steady_10_hz_stream_once_a_second() -> None:
    printed = reports(RateWindow(10000), [1.0 + 0.1 * k for k in range(25)])
    # ros2cli: nothing for the first second, then one report per second of arrivals
    assert printed == [
        "average rate: 10.000\n\tmin: 0.100s max: 0.100s std dev: 0.00000s window: 11",
        "average rate: 10.000\n\tmin: 0.100s max: 0.100s std dev: 0.00000s window: 21",
    ]


@pytest.mark.timeout(10)
def test_rate_window_of_an_uneven_stream_and_its_window_size() -> None:
    window = RateWindow(2)
    # the first report waits for a second after 1.1 s: at 2.5 s, on the last two periods
    printed = reports(window, [1.0, 1.1, 1.3, 1.6, 2.0, 2.5, 3.1])
    assert printed == [
        "average rate: 2.222\n\tmin: 0.400s max: 0.500s std dev: 0.05000s window: 2"
    ]


@pytest.mark.timeout(10)
def test_rate_window_restarts_when_the_clock_resets() -> None:
    window = RateWindow(100)
    reports(window, [5.0, 5.1])
    assert window.add(0) == "time has reset, resetting counters"
    assert window.add(0) is None and window.report() is None


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
def test_truncation_and_no_arr_like_rosidl_runtime_py() -> None:
    from uav_fault_msgs.msg import FaultEstimate

    message = FaultEstimate(names=["a", "b"], window_values_pct=[float(k) for k in range(200)])
    plain = to_plain(message, truncate_length=128)
    assert len(plain["window_values_pct"]) == 129 and plain["window_values_pct"][-1] == "..."
    assert to_plain(message)["window_values_pct"] == [float(k) for k in range(200)]
    short = to_plain(message, truncate_length=1)
    assert short["names"] == ["a", "..."]
    abbreviated = to_plain(message, no_arr=True)
    assert abbreviated["window_values_pct"] == "<sequence type: double, length: 200>"
    assert abbreviated["names"] == "<sequence type: string, length: 2>"
    assert to_plain(message, no_str=True)["header"]["frame_id"] == "<string length: <0>>"
    text = format_document(message, truncate_length=2)
    assert "- 1.0\n- '...'\n" in text


@pytest.mark.timeout(10)
def test_fixed_size_arrays_are_plain_numbers() -> None:
    from geometry_msgs.msg import PoseWithCovariance

    message = PoseWithCovariance()
    assert to_plain(message)["covariance"] == [0.0] * 36
    assert to_plain(message, no_arr=True)["covariance"] == "<array type: double[36]>"


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
def test_set_message_fields_from_yaml() -> None:
    from builtin_interfaces.msg import Time
    from diagnostic_msgs.msg import DiagnosticArray
    from uav_fault_msgs.msg import FaultVector

    message = FaultVector()
    now = Time(sec=7, nanosec=8)
    set_message_fields(message, {"header": "auto", "names": ["a"], "values_pct": [1]}, lambda: now)
    assert message.header.stamp == now and list(message.values_pct) == [1.0]
    nested = DiagnosticArray()
    values = {"header": {"frame_id": "x", "stamp": "now"},
              "status": [{"name": "n", "values": [{"key": "k", "value": "v"}]}]}
    set_message_fields(nested, values, lambda: now)
    assert nested.header.stamp == now and nested.status[0].values[0].value == "v"
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        set_message_fields(FaultVector(), {"nope": 1}, lambda: now)


@pytest.mark.timeout(10)
def test_param_get_lines_and_dump_like_ros2param() -> None:
    from rcl_interfaces.msg import ParameterValue

    assert get_line(ParameterValue(type=2, integer_value=50)) == "Integer value is: 50"
    assert get_line(ParameterValue(type=3, double_value=4.0)) == "Double value is: 4.0"
    assert get_line(ParameterValue(type=1, bool_value=False)) == "Boolean value is: False"
    doubles = ParameterValue(type=8, double_array_value=[0.5, 1.0])
    assert get_line(doubles) == "Double values are: array('d', [0.5, 1.0])"
    assert get_line(doubles, hide_type=True) == "array('d', [0.5, 1.0])"
    assert get_line(ParameterValue(type=0)) == "Parameter not set."
    names = ["qos_overrides./clock.depth", "b", "a"]
    values = [ParameterValue(type=2, integer_value=1), ParameterValue(type=4, string_value="s"),
              ParameterValue(type=9, string_array_value=["x"])]
    assert dump_text("/n", names, values) == (
        "/n:\n  ros__parameters:\n    a:\n    - x\n    b: s\n    qos_overrides:\n"
        "      /clock:\n        depth: 1\n"
    )


@pytest.mark.timeout(10)
def test_interface_show_expands_nested_types_without_their_comments() -> None:
    lines = list(interface_lines("geometry_msgs/msg/Vector3Stamped"))
    header = lines.index("std_msgs/Header header")
    assert lines[header + 1 : header + 5] == [
        "\tbuiltin_interfaces/Time stamp", "\t\tint32 sec", "\t\tuint32 nanosec",
        "\tstring frame_id",
    ]
    assert "\tfloat64 x" in lines and not any(line.startswith("\t#") for line in lines)
    bare = list(interface_lines("std_msgs/msg/Header", comments=False))
    assert bare == ["builtin_interfaces/Time stamp", "\tint32 sec", "\tuint32 nanosec",
                    "string frame_id"]
    with pytest.raises(CliError, match="Unknown package 'nope'"):
        list(interface_lines("nope/msg/X"))


@pytest.mark.timeout(10)
def test_comments_end_at_a_hash_outside_quotes() -> None:
    assert without_comment("float64 x   # metres") == "float64 x"
    assert without_comment("    # a comment line") == ""
    assert without_comment('string A="x#y"  # c') == 'string A="x#y"'
    assert without_comment("string B='#' ") == "string B='#'"


@pytest.mark.timeout(10)
def test_bag_info_text_like_rosbag2() -> None:
    def topic(name, kind, count):
        return {"message_count": count, "topic_metadata": {
            "name": name, "type": kind, "serialization_format": "cdr"}}

    metadata = {
        "relative_file_paths": ["a.mcap", "b.mcap"],
        "storage_identifier": "mcap",
        "ros_distro": "",
        "duration": {"nanoseconds": 2_050_000_000},
        "starting_time": {"nanoseconds_since_epoch": 10**18 + 7},
        "message_count": 12,
        "topics_with_message_count": [
            topic("/x", "std_msgs/msg/String", 10),
            topic("/s/_service_event", "std_srvs/srv/Empty_Event", 2),
        ],
    }
    lines = format_bag_info(metadata, 3 * 1024 * 1024).splitlines()
    assert lines[1:6] == [
        "Files:             a.mcap",
        "                   b.mcap",
        "Bag size:          3.0 MiB",
        "Storage id:        mcap",
        "ROS Distro:        unknown",
    ]
    assert lines[6] == "Duration:          2.050000000s"
    assert lines[7].endswith(".000000007 (1000000000.000000007)")
    assert lines[9:] == [
        "Messages:          10",
        "Topic information: Topic: /x | Type: std_msgs/msg/String | Count: 10 | "
        "Serialization Format: cdr",
        "Service:           1",
        "Service information: Service: /s | Type: std_srvs/srv/Empty | Event Count: 2 | "
        "Serialization Format: cdr",
    ]
    assert [format_size(n) for n in (0, 1023, 1024, 1536 * 1024)] == [
        "0 B", "1023 B", "1.0 KiB", "1.5 MiB"]


@pytest.mark.timeout(10)
def test_parser_of_the_new_verbs() -> None:
    args = parser().parse_args(["run", "pkg", "exe", "--ros-args", "-p", "rate:=2.0"])
    assert (args.package, args.executable) == ("pkg", "exe")
    assert args.arguments == ["--ros-args", "-p", "rate:=2.0"]
    pub = parser().parse_args(["topic", "pub", "-1", "/t", "std_msgs/msg/String", "{data: a}"])
    assert (pub.once, pub.times, pub.rate, pub.wait_matching_subscriptions) == (
        True, 0, 1.0, None)
    with pytest.raises(SystemExit):
        parser().parse_args(["topic", "pub", "-1", "-t", "2", "/t", "std_msgs/msg/String"])
    echo = parser().parse_args(["topic", "echo", "/t", "--no-arr", "-l", "5"])
    assert (echo.no_arr, echo.truncate_length, echo.full_length) == (True, 5, False)
    setting = parser().parse_args(["param", "set", "/n", "horizon", "60", "rate", "2"])
    assert (setting.node_name, setting.params_and_values) == ("/n", ["horizon", "60", "rate", "2"])
    getting = parser().parse_args(["param", "get", "/n", "horizon", "rate"])
    assert getting.parameter_names == ["horizon", "rate"]


@pytest.mark.timeout(10)
def test_csv_lines_like_message_to_csv() -> None:
    from uav_fault_msgs.msg import FaultVector

    vector = FaultVector(names=["lift", "drag"], values_pct=[1.5, 2.0])
    vector.header.frame_id = "ned"
    assert format_csv(vector) == "0,0,ned,lift,drag,1.5,2.0"
    assert format_csv(vector, truncate_length=1) == "0,0,n...,l...,...,1.5,..."
    assert format_csv(vector, no_arr=True, no_str=True) == (
        "0,0,<string length: <3>>,<sequence type: string, length: 2>,"
        "<sequence type: double, length: 2>"
    )


@pytest.mark.timeout(10)
def test_bandwidth_window_like_ros2topic_bw() -> None:
    window = BandwidthWindow(3)
    window.add(10.0, 100)
    assert window.report(11.0) is None  # two messages at least
    for k in range(1, 5):
        window.add(10.0 + k, 100 + k)
    # the last three messages (102, 103, 104 B) since the first of them at 12 s
    assert window.report(15.0) == (
        "103 B/s from 3 messages\n\tMessage size mean: 103 B min: 102 B max: 104 B"
    )
    big = BandwidthWindow(100)
    big.add(0.0, 2_000_000)
    big.add(0.5, 2_000_000)
    assert big.report(1.0) == (
        "4.00 MB/s from 2 messages\n\tMessage size mean: 2.00 MB min: 2.00 MB max: 2.00 MB"
    )
    assert big.report(0.0) is None and not big.arrivals  # the clock went back
