"""The project's `ros2` command against live processes: echo, list, info, hz, run."""

from __future__ import annotations

import math
import re
import time

import pytest
from helpers.echo_output import echo_documents
from helpers.ros2_cli import run_cli, run_cli_all
from helpers.samples import FRAME_ID, SAMPLE_FIELDS, STAMP_NANOSEC, STAMP_SEC, topic_of
from uav_common.ros_processes import wait_until

pytestmark = pytest.mark.integration


def assert_close(printed, expected, path: str) -> None:
    """Printed YAML values equal the sample's (floats to their printed precision)."""
    if isinstance(expected, list):
        assert isinstance(printed, list) and len(printed) == len(expected), path
        for index, (got, want) in enumerate(zip(printed, expected, strict=True)):
            assert_close(got, want, f"{path}[{index}]")
    elif isinstance(expected, float):
        assert math.isclose(printed, expected, rel_tol=1e-12, abs_tol=1e-15), (path, printed)
    else:
        assert printed == expected, (path, printed, expected)


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_echo_once_prints_every_message_type(sample_publisher, start_process) -> None:
    echoes = {
        name: start_process(
            ["ros2", "topic", "echo", topic_of(name), "--once", "--timeout", "60"], f"echo_{name}"
        )
        for name in SAMPLE_FIELDS
    }
    for name, echo in echoes.items():
        assert echo.wait(timeout_s=90) == 0, echo.output()
        document = echo_documents(echo.output())[0]
        assert document["header"] == {
            "stamp": {"sec": STAMP_SEC, "nanosec": STAMP_NANOSEC},
            "frame_id": FRAME_ID,
        }
        assert list(document)[1:] == list(SAMPLE_FIELDS[name]) or set(SAMPLE_FIELDS[name]) <= set(
            document
        ), (name, list(document))
        for field, value in SAMPLE_FIELDS[name].items():
            assert_close(document[field], value, f"{name}.{field}")
        print(f"{name}: {len(document) - 1} fields echoed and checked")


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_echo_field_prints_only_that_field(sample_publisher) -> None:
    result, nested = run_cli_all(
        ["topic", "echo", topic_of("Residuals"), "--once", "--timeout", "30",
         "--field", "residual"],
        ["topic", "echo", topic_of("WindEstimate"), "--once", "--timeout", "30",
         "--field", "header.stamp.sec"],
    )
    assert result.returncode == 0, result.stderr
    assert echo_documents(result.stdout)[0] == SAMPLE_FIELDS["Residuals"]["residual"]
    assert echo_documents(nested.stdout) == [STAMP_SEC], nested.stdout


@pytest.mark.timeout(60)
def test_echo_unknown_field_is_one_clear_error(sample_publisher) -> None:
    result = run_cli(
        "topic",
        "echo",
        topic_of("Residuals"),
        "--once",
        "--timeout",
        "30",
        "--field",
        "residual.nope",
    )
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    last_line = result.stderr.strip().splitlines()[-1]
    assert last_line == "Invalid field 'residual.nope': no field 'nope'"


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_topic_list_info_and_node_list(sample_publisher) -> None:
    listing, info, nodes = run_cli_all(
        ["topic", "list", "-t"], ["topic", "info", topic_of("FaultEstimate")], ["node", "list"]
    )
    assert listing.returncode == 0, listing.stderr
    for name in SAMPLE_FIELDS:
        assert f"/{topic_of(name)} [uav_fault_msgs/msg/{name}]" in listing.stdout.splitlines()
    assert info.stdout.splitlines() == [
        "Type: uav_fault_msgs/msg/FaultEstimate",
        "Publisher count: 1",
        "Subscription count: 0",
    ]
    assert "/sample_publisher" in nodes.stdout.splitlines()
    assert not any(line.startswith("/_") for line in nodes.stdout.splitlines())


def rate_reports(output: str) -> list[float]:
    """The average rates `ros2 topic hz` has printed."""
    return [float(value) for value in re.findall(r"average rate: ([0-9.]+)", output)]


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_topic_hz_reports_the_publish_rate(sample_publisher, start_process) -> None:
    # a report a second over the last 30 arrivals (3 s): the sixth's window lies past the
    # first arrivals, which discovery under load can hold back and deliver in a burst
    rate = start_process(["ros2", "topic", "hz", topic_of("AircraftState"), "--window", "30"],
                         "hz")
    assert wait_until(lambda: len(rate_reports(rate.output())) >= 6, timeout_s=40), rate.output()
    assert rate.stop() == 0, rate.output()
    rates = rate_reports(rate.output())
    print("ros2 topic hz reported:", rates)
    assert rates, rate.output()
    assert rates[-1] == pytest.approx(10.0, rel=0.1)
    assert "std dev:" in rate.output() and "Traceback" not in rate.output()


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_echo_of_a_missing_topic_waits_like_ros2cli(start_process, ros_graph) -> None:
    echo = start_process(["ros2", "topic", "echo", "no_such_topic"], "echo_waiting")
    assert wait_until(lambda: "does not appear to be published yet" in echo.output(),
                      timeout_s=30), echo.output()
    # warned, and still waiting for the topic 4 s on, as ros2cli's echo does
    assert not wait_until(lambda: not echo.running(), timeout_s=4.0), echo.output()
    assert echo.stop() == 0 and "Traceback" not in echo.output()


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_echo_once_with_timeout_of_a_missing_topic_fails_clearly(ros_graph) -> None:
    started = time.monotonic()
    result = run_cli("topic", "echo", "no_such_topic", "--once", "--timeout", "2")
    waited_s = time.monotonic() - started
    assert result.returncode == 1
    assert result.stderr.strip().splitlines()[-1] == (
        "Could not determine the type for the passed topic [/no_such_topic] within 2.0 s"
    )
    assert "Traceback" not in result.stderr and waited_s >= 2.0


@pytest.mark.timeout(30)
@pytest.mark.parametrize(
    ("package", "executable", "message"),
    [
        ("no_such_package", "node", "Package 'no_such_package' not found"),
        ("uav_sim", "no_such_node", "No executable found: 'no_such_node' in package 'uav_sim'"),
    ],
)
def test_run_of_unknown_package_or_executable_fails_clearly(package, executable, message) -> None:
    result = run_cli("run", package, executable)
    assert result.returncode == 1
    assert result.stderr.strip() == message
