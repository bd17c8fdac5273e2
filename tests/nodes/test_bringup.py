"""scripts/bringup.sh: the nodes live under a namespace, and Ctrl-C on the script alone
stops every one of them."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest
from helpers.process_table import NODE_NAMES, kill_all, processes
from ros_processes import wait_until
from uav_fault_msgs.msg import FaultEstimate
from uav_sim.ros.node_tools import STREAM_QOS

pytestmark = pytest.mark.integration

BRINGUP = Path(__file__).resolve().parents[2] / "scripts" / "bringup.sh"


@pytest.mark.timeout(120)
def test_bringup_runs_the_nodes_and_ctrl_c_stops_them_all(
        start_process, short_scenario, graph, ros_domain, tmp_path) -> None:
    logs = tmp_path / "logs"

    def leftovers() -> list:
        return processes(lambda info: str(logs) in info.cmdline or (
            any(name in info.cmdline for name in NODE_NAMES)
            and info.environ.get("ROS_DOMAIN_ID") == str(ros_domain)))

    estimates = graph.subscribe({"/uav2/faults/estimate": FaultEstimate}, STREAM_QOS)[
        "/uav2/faults/estimate"]
    bringup = start_process([str(BRINGUP), "--ns", "/uav2", "--scenario",
                             str(short_scenario(60.0)), "--logs", str(logs)], "bringup")
    try:
        graph.spin(60.0, until=lambda: len(estimates) >= 2 or not bringup.running())
        assert len(estimates) >= 2, bringup.output()
        assert estimates[-1].names == list(estimates[0].names)
        output = bringup.output()
        assert str(logs) in output and "ros2 topic echo /uav2/faults/estimate" in output
        assert {path.name for path in logs.glob("*_node.log")} == {
            "sim_node.log", "residual_node.log", "mhe_node.log", "detector_node.log"}

        os.kill(bringup.pid, signal.SIGINT)  # the script only, not its group
        assert bringup.wait(15) == 130, bringup.output()
        assert wait_until(lambda: not leftovers(), timeout_s=1.0), leftovers()
        print(bringup.output())
    finally:
        kill_all(leftovers())
