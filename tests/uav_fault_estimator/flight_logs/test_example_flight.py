"""The example flight the project ships (examples/flights/): docs/flight_logs.md's commands
run on it as the page writes them, from a folder laid out as the repository root (the
screening, the benchmark, and the graph: detector_node beside log_replay_node, this test
taking the alarms the page echoes), and what they find is what the page says; the shipped
files are what tools/example_flight.py writes."""

from __future__ import annotations

import csv
import json
import math
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from helpers.repo import REPO_ROOT
from uav_common.message_fields import stamp_seconds
from uav_common.ros.qos import STREAM_QOS
from uav_fault_msgs.msg import FaultAlarm

PAGE = REPO_ROOT / "docs" / "flight_logs.md"
EXAMPLE = "examples/flights/"
FLIGHT = "aerosonde_sim_aileron_failure"
ONSET_S = 55.0  # tools/example_flight.py's, in simulation time: the log's clock less 0-20 ms
MAX_EXAMPLE_BYTES = 400 * 1024  # "a few hundred KB at most"


def example_blocks() -> list[str]:
    """The page's sh blocks that run on the example, in page order."""
    blocks = re.findall(r"```sh\n(.*?)```", PAGE.read_text(), re.DOTALL)
    return [block for block in blocks if EXAMPLE in block]


def block_with(word: str) -> str:
    (block,) = [block for block in example_blocks() if word in block]
    return block


def commands(block: str) -> list[list[str]]:
    """A block's commands as argument lists: continuations joined, comments dropped."""
    joined = block.replace("\\\n", " ")
    return [shlex.split(line, comments=True) for line in joined.splitlines() if line.strip()]


@pytest.fixture
def root(tmp_path: Path) -> Path:
    """A folder laid out as the repository root for the page's relative paths (links to the
    checkout's folders); what the commands write lands in it, not in the checkout."""
    for name in ("examples", "ros_ws", "scripts"):
        (tmp_path / name).symlink_to(REPO_ROOT / name)
    return tmp_path


def outcome_of(screened: Path) -> dict:
    """The example's outcome against its truth in a screening's summary.json."""
    (log,) = json.loads((screened / "summary.json").read_text())["logs"]
    return log["outcome"]


def run_block(block: str, root: Path) -> subprocess.CompletedProcess:
    result = subprocess.run(["bash", "-e", "-c", block], cwd=root, capture_output=True,
                            text=True, timeout=100)
    print(result.stdout, result.stderr)
    return result


@pytest.mark.timeout(10)
def test_the_example_is_small_and_an_alfa_flight_folder_with_its_truth():
    folder = REPO_ROOT / EXAMPLE / FLIGHT
    files = sorted(path.name for path in folder.iterdir())
    assert all(name.startswith(f"{FLIGHT}-") and name.endswith(".csv") for name in files)
    assert f"{FLIGHT}-failure_status-aileron.csv" in files
    assert sum(path.stat().st_size for path in folder.iterdir()) < MAX_EXAMPLE_BYTES


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_the_pages_screening_runs_on_the_example_and_finds_what_it_says(root: Path):
    result = run_block(block_with("screen_logs.py screen"), root)
    assert result.returncode == 0, result.stderr
    table = (root / "screened" / f"{FLIGHT}.alarms.csv").read_text()
    assert table.startswith("start_s,end_s,channel,test,samples")
    assert re.search(r"^ +start_s +end_s +channel", result.stdout, re.MULTILINE)  # column's
    outcome = outcome_of(root / "screened")
    # the page: found 3.4 s after its onset, on roll, with the Aerosonde's calibration
    assert (outcome["outcome"], round(outcome["delay_s"], 1), outcome["first_alarm_channel"]) \
        == ("tp", 3.4, "roll")
    # and: the flight's own 50 s before the failure calibrate it too narrowly to trust
    own = subprocess.run([sys.executable, "scripts/screen_logs.py", "screen", EXAMPLE,
                          "--calibration", "example_cal.yaml", "--airframe",
                          "ros_ws/src/uav_aircraft/aircraft/aerosonde/airframes/aerosonde_sim.yaml",
                          "--out", "own"], cwd=root, capture_output=True, text=True,
                         timeout=60)
    assert own.returncode == 0, own.stderr
    assert outcome_of(root / "own")["outcome"] == "fp"


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_the_pages_benchmark_runs_on_the_example(root: Path):
    result = run_block(block_with("alfa_benchmark.py examples"), root)
    assert result.returncode == 0, result.stderr
    assert f"{FLIGHT}" in result.stdout and "aileron" in result.stdout
    # the page: calibrated on its own 50 s, the flight alarms before its onset
    assert "at any delay: tp 0, fp 1, fn 0, tn 0" in result.stdout


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.timeout(120)
def test_the_pages_graph_replays_the_example_to_the_detectors_alarms(root: Path, graph,
                                                                    start_process):
    """The page's two `ros2 run` lines as written; its `ros2 topic echo` is this test's
    subscription, matched before the replay starts."""
    detector, replay, echo = commands(block_with("log_replay_node"))
    assert echo[:3] == ["ros2", "topic", "echo"] and echo[3] == "faults/alarm"
    alarms = graph.subscribe({"/faults/alarm": FaultAlarm}, STREAM_QOS)["/faults/alarm"]
    start_process(["bash", "-c", f"cd {shlex.quote(str(root))} && exec {shlex.join(detector)}"],
                  "detector_node")
    assert graph.wait_for_publishers("/faults/alarm", 1, timeout_s=30)
    replaying = start_process(["bash", "-c", f"cd {shlex.quote(str(root))} && exec "
                               f"{shlex.join(replay)}"], "log_replay_node")
    assert replaying.wait(timeout_s=60) == 0, replaying.output()
    graph.spin(20.0, until=lambda: alarms and stamp_seconds(alarms[-1].header.stamp) > 79.0)
    combined = [stamp_seconds(m.header.stamp) for m in alarms if m.combined_alarm]
    print(f"{len(alarms)} alarm messages, combined alarms from {combined[:1]} s")
    assert combined and min(combined) >= ONSET_S - 0.1  # none before the failure


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_the_shipped_example_is_what_its_tool_writes(tmp_path: Path):
    subprocess.run([sys.executable, str(REPO_ROOT / "tools" / "example_flight.py"), "--out",
                    str(tmp_path)], check=True, capture_output=True, timeout=100)
    shipped = REPO_ROOT / EXAMPLE / FLIGHT
    written = tmp_path / FLIGHT
    assert sorted(p.name for p in written.iterdir()) == sorted(p.name for p in shipped.iterdir())
    for path in shipped.iterdir():
        ours, theirs = (list(csv.reader((folder / path.name).open()))
                        for folder in (written, shipped))
        assert len(ours) == len(theirs) and ours[0] == theirs[0], path.name
        for row, other in zip(ours[1:], theirs[1:], strict=True):
            assert all(a == b or math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-12)
                       for a, b in zip(row, other, strict=True)), (path.name, row, other)
