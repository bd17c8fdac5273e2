"""The `ros2` stand-in's service verbs against a live mhe_node's parameter services."""

from __future__ import annotations

import re
import time

import pytest
from helpers.ros2_cli import run_cli, run_cli_all
from uav_common.ros_processes import wait_until

pytestmark = pytest.mark.integration

PARAMETER_SERVICES = {
    "describe_parameters": "rcl_interfaces/srv/DescribeParameters",
    "get_parameter_types": "rcl_interfaces/srv/GetParameterTypes",
    "get_parameters": "rcl_interfaces/srv/GetParameters",
    "list_parameters": "rcl_interfaces/srv/ListParameters",
    "set_parameters": "rcl_interfaces/srv/SetParameters",
    "set_parameters_atomically": "rcl_interfaces/srv/SetParametersAtomically",
}


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_service_list_and_type_show_the_parameter_services(mhe_node) -> None:
    typed, listed, count, type_of, unknown = run_cli_all(
        ["service", "list", "-t"], ["service", "list"], ["service", "list", "-c"],
        ["service", "type", "/mhe_node/get_parameters"],
        ["service", "type", "/mhe_node/no_such_service", "--spin-time", "1"],
    )
    assert typed.returncode == 0, typed.stderr
    lines = typed.stdout.splitlines()
    assert lines == sorted(lines)
    for name, kind in PARAMETER_SERVICES.items():
        assert f"/mhe_node/{name} [{kind}]" in lines, lines
    names = listed.stdout.splitlines()
    assert names == [line.split(" [")[0] for line in lines]
    assert count.stdout == f"{len(names)}\n"
    assert (type_of.returncode, type_of.stdout) == (0, "rcl_interfaces/srv/GetParameters\n")
    assert unknown.returncode == 1 and unknown.stdout == "" and "Traceback" not in unknown.stderr


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_service_call_prints_request_and_response_like_ros2cli(mhe_node) -> None:
    result, short_type = run_cli_all(
        ["service", "call", "/mhe_node/get_parameters", "rcl_interfaces/srv/GetParameters",
         "{names: [horizon, use_sim_time]}"],
        ["service", "call", "/mhe_node/list_parameters",
         "rcl_interfaces/ListParameters"],  # pkg/Name, and no YAML: defaults
    )
    assert result.returncode == 0, result.stderr
    # "waiting for service..." first when discovery has not yet found the server
    body = result.stdout.removeprefix("waiting for service to become available...\n")
    request = ("requester: making request: "
               "rcl_interfaces.srv.GetParameters_Request(names=['horizon', 'use_sim_time'])\n\n")
    assert body.startswith(request), body
    response = body[len(request):]
    assert response.startswith("response:\nrcl_interfaces.srv.GetParameters_Response(values=[")
    values = re.findall(r"ParameterValue\(type=(\d+), bool_value=(\w+), integer_value=(\d+)",
                        response)
    assert values == [("2", "False", "50"), ("1", "False", "0")], response
    assert response.endswith(")])\n\n")

    assert short_type.returncode == 0, short_type.stderr
    assert re.search(r"ListParametersResult\(names=\[[^]]*'noise_variance_factor'",
                     short_type.stdout), short_type.stdout


RATE_PERIODS = 12  # 3 s at 4 Hz: a poll step and a late response each shift it by < 3 %
POLL_S = 0.02


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_service_call_repeats_at_the_rate(mhe_node, start_process) -> None:
    caller = start_process(["ros2", "service", "call", "-r", "4", "/mhe_node/get_parameters",
                            "rcl_interfaces/srv/GetParameters", "{names: [horizon]}"], "call_rate")

    def responses() -> int:
        return caller.output().count("response:\n")

    # the rate from the time the next RATE_PERIODS responses take after the first (start-up
    # and discovery left out), timed by polling the output at a fine step
    assert wait_until(lambda: responses() >= 1, timeout_s=30, poll_s=POLL_S), caller.output()
    first = responses()
    started = time.monotonic()
    assert wait_until(lambda: responses() >= first + RATE_PERIODS, timeout_s=30,
                      poll_s=POLL_S), caller.output()
    rate_hz = (responses() - first) / (time.monotonic() - started)
    assert caller.stop() == 0, caller.output()
    print(f"-r 4: {rate_hz:.2f} responses a second")
    assert rate_hz == pytest.approx(4.0, rel=0.2) and "Traceback" not in caller.output()


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["rcl_interfaces/srv/NoSuch"], "The passed service type is invalid"),
        (["rcl_interfaces/msg/Log"], "The passed type is not a service"),
        (["rcl_interfaces/srv/GetParameters", "{nams: [a]}"],
         "Failed to populate field: 'GetParameters_Request' object has no attribute 'nams'"),
        (["rcl_interfaces/srv/GetParameters", "-r", "0"], "rate must be greater than zero"),
    ],
)
def test_service_call_errors_are_one_line(arguments, message, ros_domain) -> None:
    result = run_cli("service", "call", "/nobody/get_parameters", *arguments)
    assert (result.returncode, result.stdout, result.stderr) == (1, "", message + "\n")
