"""demo.sh --via-mavlink: the default flight, cut short, through the simulated ArduPlane's
link and mavlink_node to the chain, reported against the seeded faults as the plain demo
reports it: every estimate the link can carry arrives, the truth is recorded at its own
names, and each node's output is in the logs."""

from __future__ import annotations

import json

import pytest
from helpers.process_table import kill_all, nodes_logging_under
from helpers.repo import SCRIPTS
from uav_fault_estimator.reporting.report import residual_update_period_s
from uav_sim.scenario import default_scenario_path

pytestmark = pytest.mark.integration

DURATION_S = 40.0  # at the link's pace of 10 times real time: 4 s of flight
SAMPLE_PERIOD_S = 0.05  # the last sample stays on the link (mavlink_node)
EXIT_TARGET_MISSED = 3  # no fault is reached this early: judged on its false alarms alone


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_a_short_flight_through_the_arduplane_link_is_reported(start_process, tmp_path):
    out = tmp_path / "run"
    try:
        demo = start_process([str(SCRIPTS / "demo.sh"), str(default_scenario_path()),
                              "--via-mavlink", "ardupilot", "--duration", f"{DURATION_S:g}",
                              "--out", str(out)], "demo")
        status = demo.wait(100)
        output = demo.output()
        print(output)
        assert status in (0, EXIT_TARGET_MISSED), output
        assert "estimates of mhe_node arrived" not in output  # none missing
    finally:
        kill_all(nodes_logging_under(tmp_path))
    metrics = json.loads((out / "metrics.json").read_text())
    expected = round(DURATION_S / residual_update_period_s())  # as the plain demo: all
    assert metrics["pipeline"]["messages_received"] == expected
    assert metrics["duration_s"] == pytest.approx(DURATION_S)
    assert {path.name for path in (out / "logs").glob("*.log")} == {
        f"{node}.log" for node in ("sim_node", "autopilot_node", "mavlink_node",
                                   "residual_node", "mhe_node", "detector_node",
                                   "recorder_node")}
    assert "heard ArduPilot as system 1" in (out / "logs" / "mavlink_node.log").read_text()
