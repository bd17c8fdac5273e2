"""Every node ends cleanly (status 0, no traceback) on SIGINT and on SIGTERM, also when it
was started with SIGINT ignored, as `cmd &` in a non-interactive script leaves it.

Before run_node handled the signals itself, rclpy's handlers shut the context down under
the running node: sim_node, mid-flight, ended with `RCLError: Failed to publish:
publisher's context is invalid` and status 1 (SIGINT ignored, or SIGTERM).
"""

from __future__ import annotations

import re
import signal
import subprocess
import sys

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from helpers.diagnostics import recorded_count
from uav_common.ros.node_life import STUCK_STOP_S
from uav_common.ros.qos import DIAGNOSTICS_QOS, STREAM_QOS
from uav_common.ros_processes import ros2_run_argv, stop_all, wait_until
from uav_fault_msgs.msg import AircraftState

pytestmark = pytest.mark.integration

# `trap "" INT` sets SIGINT to SIG_IGN and exec keeps it so: what a non-interactive shell
# gives a command it starts with `&`.
SIGINT_IGNORED = ["bash", "-c", 'trap "" INT; exec "$@"', "bash"]
REAL_TIME_FACTOR = 20.0  # the default 300 s scenario takes 15 s of wall time: mid-flight
CLOSED = re.compile(r"recording closed in \S+: (.*)")
CHAIN = ("/state", "/residuals", "/faults/estimate", "/faults/alarm")  # sim to estimates
STATES_PER_S = 20  # sim_node's default sensor rate [Hz]


def sim_argv(subscribers: int) -> list[str]:
    return ros2_run_argv("uav_sim", "sim_node", ros_args=[
        "-p", f"real_time_factor:={REAL_TIME_FACTOR}",
        "-p", f"wait_for_subscribers:={subscribers}"])


def flying(sim) -> bool:
    return "real-time factor" in sim.output() and "finished" not in sim.output()


@pytest.mark.timeout(10)
def test_the_wrapper_starts_a_command_with_sigint_ignored():
    """What the node inherits (run_node then takes SIGINT again)."""
    result = subprocess.run([*SIGINT_IGNORED, "grep", "^SigIgn:", "/proc/self/status"],
                            capture_output=True, text=True, timeout=5, check=True)
    assert int(result.stdout.split()[1], 16) & (1 << (signal.SIGINT - 1)), result.stdout


@pytest.mark.timeout(90)
@pytest.mark.slow
@pytest.mark.parametrize(("sig", "ignore_sigint"), [
    (signal.SIGINT, True), (signal.SIGINT, False), (signal.SIGTERM, False),
    (signal.SIGTERM, True)])
def test_sim_node_mid_flight_ends_cleanly(start_process, graph, sig, ignore_sigint):
    states = graph.subscribe({"/state": AircraftState}, STREAM_QOS)["/state"]
    prefix = SIGINT_IGNORED if ignore_sigint else []
    sim = start_process(prefix + sim_argv(subscribers=1), "sim_node")  # once we listen
    assert graph.wait("a second of flight published", lambda: len(states) >= STATES_PER_S
                      or not sim.running(), timeout_s=40), sim.output()
    assert sim.running() and flying(sim), sim.output()
    status = sim.stop(sig)
    output = sim.output()
    print(output)
    assert status == 0, output
    assert "Traceback" not in output and "Error" not in output
    assert "finished" not in output  # it was stopped mid-flight, not at the scenario's end


@pytest.mark.slow
@pytest.mark.timeout(120)
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_the_whole_graph_started_in_the_background_ends_cleanly(start_process, graph,
                                                                tmp_path, sig):
    """Every node of the main job, SIGINT ignored as `&` leaves it, stopped while messages
    flow between them: status 0 each, no traceback, the recording closed with messages."""
    diagnostics = graph.subscribe({"/diagnostics": DiagnosticArray}, DIAGNOSTICS_QOS)[
        "/diagnostics"]
    bag = tmp_path / "bag"
    nodes = {
        name: start_process(SIGINT_IGNORED + ros2_run_argv(
            "uav_fault_estimator", name, ros_args=args), name)
        for name, args in [("recorder_node", ["-p", f"output_dir:={bag}"]),
                           ("residual_node", []), ("mhe_node", []), ("detector_node", [])]}
    # state subscribers: residual_node, detector_node, recorder_node
    nodes["sim_node"] = start_process(SIGINT_IGNORED + sim_argv(subscribers=3), "sim_node")
    sim = nodes["sim_node"]
    # stopped once messages have flowed along the whole chain into the recording
    assert graph.wait(f"messages of {CHAIN} in the recording", lambda: all(
        recorded_count(diagnostics, topic) > 0 for topic in CHAIN) or not sim.running(),
        timeout_s=60)
    assert all(node.running() for node in nodes.values()), {
        name: node.output() for name, node in nodes.items() if not node.running()}
    assert flying(sim), sim.output()

    statuses = dict(zip(nodes, stop_all(list(nodes.values()), sig), strict=True))
    outputs = {name: node.output() for name, node in nodes.items()}
    for name, output in outputs.items():
        print(f"--- {name}: status {statuses[name]}\n{output}")
    assert statuses == dict.fromkeys(nodes, 0), outputs
    for name, output in outputs.items():
        assert "Traceback" not in output and "context is invalid" not in output, (name, output)
    closed = CLOSED.search(outputs["recorder_node"])
    assert closed, outputs["recorder_node"]
    counts = dict(re.findall(r"(\S+) (\d+)", closed.group(1)))
    # messages flowed along the whole chain: sim -> residuals -> estimates, and alarms
    for topic in CHAIN:
        assert int(counts[topic]) > 0, counts
    assert (bag / "metadata.yaml").exists()


# A node whose run loop, once stopped, hangs (as a call into the middleware might).
HANGING_NODE = """
import time
from rclpy.node import Node
from uav_common.ros.node_life import Stopped, run_node

def run(node):
    print("running", flush=True)
    try:
        while True:
            time.sleep(0.05)
    except Stopped:
        time.sleep(60)  # hangs in its clean-up, where it cannot be stopped again

run_node("hanging_node", lambda: Node("hanging_node"), run)
"""


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_a_node_hanging_after_a_stop_prints_where(start_process):
    """A node still running STUCK_STOP_S after SIGINT prints every thread's stack on
    stderr, before stop_all kills it: the log of a hang says where it hung."""
    node = start_process([sys.executable, "-c", HANGING_NODE], "hanging_node")
    assert wait_until(lambda: "running" in node.output(), timeout_s=30), node.output()
    node.send_signal(signal.SIGINT)
    assert wait_until(lambda: "most recent call first" in node.output(),
                      timeout_s=STUCK_STOP_S + 5), node.output()
    output = node.output()
    assert "in run" in output and node.running(), output  # it says where, and still hangs
    node.send_signal(signal.SIGKILL)
