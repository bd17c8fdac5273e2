"""Nothing but loopback is contacted: a short pub/sub run of two processes under strace."""

from __future__ import annotations

import ipaddress
import re
import shutil
import sys
from pathlib import Path

import pytest
from helpers.echo_output import echo_documents
from helpers.samples import SAMPLE_FIELDS, topic_of

pytestmark = pytest.mark.integration

# Only calls that name a destination; bind() names a local address and contacts no one.
DESTINATION_CALL = re.compile(r"^\d+\s+(connect|sendto|sendmsg|sendmmsg)\(")
INET_ADDRESS = re.compile(r'inet_addr\("([^"]+)"\)|inet_pton\(AF_INET6, "([^"]+)"')
TRACE = ["strace", "-f", "-qq", "-e", "trace=connect,sendto,sendmsg,sendmmsg", "-o"]


def destinations(trace_path: Path) -> list[str]:
    """Every IPv4/IPv6 destination address in an strace log of network calls."""
    found = []
    for line in trace_path.read_text().splitlines():
        if DESTINATION_CALL.match(line):
            found += [v4 or v6 for v4, v6 in INET_ADDRESS.findall(line)]
    return found


@pytest.mark.timeout(90)
def test_pub_sub_contacts_only_loopback(start_process, ros_graph, tmp_path) -> None:
    if shutil.which("strace") is None:
        pytest.skip("strace is not installed (Debian: apt-get install strace)")
    publisher_trace, echo_trace = tmp_path / "publisher.trace", tmp_path / "echo.trace"
    start_process(
        [*TRACE, str(publisher_trace), sys.executable, "tests/helpers/sample_publisher.py"],
        "publisher",
    )
    echo = start_process(
        [
            *TRACE,
            str(echo_trace),
            "ros2",
            "topic",
            "echo",
            topic_of("FaultVector"),
            "--once",
            "--timeout",
            "60",
        ],
        "echo",
    )
    assert echo.wait(timeout_s=80) == 0, echo.output()
    received = echo_documents(echo.output())[0]
    assert received["names"] == SAMPLE_FIELDS["FaultVector"]["names"]  # data really flowed

    addresses = destinations(publisher_trace) + destinations(echo_trace)
    counts = {address: addresses.count(address) for address in set(addresses)}
    print("datagram and connection destinations (address: count):", counts)
    assert len(addresses) > 10, "the trace saw almost no DDS traffic: is the test still valid?"
    assert all(ipaddress.ip_address(address).is_loopback for address in addresses), counts
