"""The `ros2` stand-in's topic list -c/-v, type, find, bw, node list -c and echo's output
options, against the sample publisher (every message type at 10 Hz)."""

from __future__ import annotations

import re

import pytest
import yaml
from helpers.echo_output import echo_documents
from helpers.ros2_cli import run_cli_all
from helpers.samples import (
    FRAME_ID,
    SAMPLE_FIELDS,
    STAMP_NANOSEC,
    STAMP_SEC,
    build_sample,
    topic_of,
)
from uav_common.ros_processes import wait_until

pytestmark = pytest.mark.integration

VECTOR = topic_of("FaultVector")
VECTOR_TYPE = "uav_fault_msgs/msg/FaultVector"


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_topic_list_count_verbose_type_find_and_node_count(sample_publisher) -> None:
    listing, count, verbose, kind, unknown, found, found_count, nothing, node_count = run_cli_all(
        ["topic", "list"], ["topic", "list", "-c"], ["topic", "list", "-v"],
        ["topic", "type", VECTOR], ["topic", "type", "/no_such_topic", "--spin-time", "1"],
        ["topic", "find", VECTOR_TYPE], ["topic", "find", VECTOR_TYPE, "-c"],
        ["topic", "find", "std_msgs/msg/Nothing"], ["node", "list", "-c"],
    )
    names = listing.stdout.splitlines()
    assert "/" + VECTOR in names
    assert count.stdout == f"{len(names)}\n"
    assert verbose.returncode == 0, verbose.stderr
    published, subscribed = verbose.stdout.split("\n\n")[:2]
    assert published.splitlines()[0] == "Published topics:"
    assert f" * /{VECTOR} [{VECTOR_TYPE}] 1 publisher" in published.splitlines()
    assert len(published.splitlines()) == len(names) + 1  # every topic has a publisher
    assert subscribed == "Subscribed topics:"  # nobody subscribes to the samples
    assert verbose.stdout.endswith("\n\n")

    assert (kind.returncode, kind.stdout) == (0, VECTOR_TYPE + "\n")
    assert unknown.returncode == 1 and unknown.stdout == "" and "Traceback" not in unknown.stderr
    assert (found.returncode, found.stdout) == (0, f"/{VECTOR}\n")
    assert found_count.stdout == "1\n"
    assert nothing.stdout == ""
    assert node_count.stdout == "1\n"


def bw_reports(output: str) -> list[tuple[str, ...]]:
    """The reports `ros2 topic bw` has printed: rate, unit, message count, then the mean,
    min and max sizes, each with its unit."""
    return re.findall(r"([0-9.]+) (B|KB)/s from (\d+) messages\n\tMessage size mean: "
                      r"([0-9.]+) (B|KB) min: ([0-9.]+) (B|KB) max: ([0-9.]+) (B|KB)", output)


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_topic_bw_reports_the_serialised_bytes_per_second(sample_publisher,
                                                          start_process) -> None:
    from rclpy.serialization import serialize_message

    size = len(serialize_message(build_sample("FaultAlarm")))
    bandwidth = start_process(["ros2", "topic", "bw", topic_of("FaultAlarm")], "bw")
    # a report a second, on the last (up to 100) messages: until one covers 3 s of them
    assert wait_until(lambda: any(int(report[2]) >= 30
                                  for report in bw_reports(bandwidth.output())),
                      timeout_s=40), bandwidth.output()
    assert bandwidth.stop() == 0, bandwidth.output()
    output = bandwidth.output()
    assert f"Subscribed to [/{topic_of('FaultAlarm')}]" in output.splitlines()
    reports = bw_reports(output)
    print(f"bw of {size} B messages at 10 Hz:", reports[-1] if reports else output)
    assert reports and "Traceback" not in output
    rate, unit, count, mean, mean_unit = reports[-1][:5]
    scale = {"B": 1, "KB": 1000}
    assert int(count) >= 20
    assert float(mean) * scale[mean_unit] == pytest.approx(size, abs=10)
    assert float(rate) * scale[unit] == pytest.approx(10 * size, rel=0.15)


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_echo_csv_flow_style_and_message_info(sample_publisher) -> None:
    sample = SAMPLE_FIELDS["FaultVector"]
    csv, flow, informed, informed_csv = run_cli_all(
        ["topic", "echo", VECTOR, "--once", "--csv"],
        ["topic", "echo", VECTOR, "--once", "--flow-style"],
        ["topic", "echo", VECTOR, "--once", "-i"],
        ["topic", "echo", VECTOR, "--once", "-i", "--csv"],
    )
    values = [str(STAMP_SEC), str(STAMP_NANOSEC), FRAME_ID, *sample["names"],
              *[str(v) for v in sample["values_pct"]]]
    assert (csv.returncode, csv.stdout) == (0, ",".join(values) + "\n"), csv.stderr

    text, separator = flow.stdout.rsplit("\n", 2)[:2]
    assert separator == "---" and text.startswith("{header: {stamp: {sec: ")
    assert "\n" not in text and yaml.safe_load(text)["names"] == sample["names"]

    info, message = echo_documents(informed.stdout)
    assert {"source_timestamp", "received_timestamp", "publication_sequence_number"} <= set(info)
    assert 0 < info["received_timestamp"] - info["source_timestamp"] < 5e9
    assert message["names"] == sample["names"]
    fields = informed_csv.stdout.strip().split(",")
    assert fields[len(info):] == values and fields[0] == str(int(fields[0]))


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_echo_filter_and_qos_options(sample_publisher) -> None:
    names = SAMPLE_FIELDS["FaultVector"]["names"]
    kept, dropped, on_field, broken, reliable, preset, unmatched, wrong = run_cli_all(
        ["topic", "echo", VECTOR, "--once", "--filter", f"m.names[0] == {names[0]!r}"],
        ["topic", "echo", VECTOR, "--timeout", "2", "--filter", "len(m.names) > 99"],
        ["topic", "echo", VECTOR, "--once", "--field", "values_pct", "--filter", "max(m) > 0"],
        ["topic", "echo", VECTOR, "--once", "--filter", "m.nope"],
        # the publisher offers reliable, volatile, keep-last: these requests all match it
        ["topic", "echo", VECTOR, "--once", "--qos-reliability", "reliable",
         "--qos-durability", "volatile", "--qos-history", "keep_last", "--qos-depth", "1",
         "--field", "header.frame_id"],
        ["topic", "echo", VECTOR, "--once", "--qos-profile", "system_default",
         "--field", "header.frame_id"],
        # a transient-local request cannot match a volatile publisher: nothing arrives
        ["topic", "echo", VECTOR, "--timeout", "2", "--qos-durability", "transient_local"],
        ["topic", "echo", VECTOR, "--qos-profile", "nope"],
    )
    assert echo_documents(kept.stdout)[0]["names"] == names
    assert (dropped.returncode, dropped.stdout) == (0, "")
    assert echo_documents(on_field.stdout) == [SAMPLE_FIELDS["FaultVector"]["values_pct"]]
    assert broken.returncode == 1 and len(broken.stderr.splitlines()) == 1, broken.stderr
    assert "Traceback" not in broken.stderr
    assert echo_documents(reliable.stdout) == [FRAME_ID], reliable.stderr
    assert echo_documents(preset.stdout) == [FRAME_ID], preset.stderr
    assert (unmatched.returncode, unmatched.stdout) == (0, "")
    assert wrong.returncode == 2 and "invalid choice: 'nope'" in wrong.stderr
