"""The `ros2` stand-in's service verbs against a live mhe_node's parameter services."""

from __future__ import annotations

import re
import time

import pytest
from helpers.ros2_cli import run_cli

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
    typed = run_cli("service", "list", "-t")
    assert typed.returncode == 0, typed.stderr
    lines = typed.stdout.splitlines()
    assert lines == sorted(lines)
    for name, kind in PARAMETER_SERVICES.items():
        assert f"/mhe_node/{name} [{kind}]" in lines, lines
    names = run_cli("service", "list").stdout.splitlines()
    assert names == [line.split(" [")[0] for line in lines]
    count = run_cli("service", "list", "-c")
    assert count.stdout == f"{len(names)}\n"
    kind = run_cli("service", "type", "/mhe_node/get_parameters")
    assert (kind.returncode, kind.stdout) == (0, "rcl_interfaces/srv/GetParameters\n")
    unknown = run_cli("service", "type", "/mhe_node/no_such_service", "--spin-time", "1")
    assert unknown.returncode == 1 and unknown.stdout == "" and "Traceback" not in unknown.stderr


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_service_call_prints_request_and_response_like_ros2cli(mhe_node) -> None:
    result = run_cli("service", "call", "/mhe_node/get_parameters",
                     "rcl_interfaces/srv/GetParameters", "{names: [horizon, use_sim_time]}")
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

    short_type = run_cli("service", "call", "/mhe_node/list_parameters",
                         "rcl_interfaces/ListParameters")  # pkg/Name, and no YAML: defaults
    assert short_type.returncode == 0, short_type.stderr
    assert re.search(r"ListParametersResult\(names=\[[^]]*'noise_variance_factor'",
                     short_type.stdout), short_type.stdout


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_service_call_repeats_at_the_rate(mhe_node, start_process) -> None:
    caller = start_process(["ros2", "service", "call", "-r", "4", "/mhe_node/get_parameters",
                            "rcl_interfaces/srv/GetParameters", "{names: [horizon]}"], "call_rate")
    time.sleep(5.0)
    assert caller.stop() == 0, caller.output()
    responses = caller.output().count("response:\n")
    print("responses in 5 s at -r 4:", responses)
    assert 8 <= responses <= 21 and "Traceback" not in caller.output()


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
