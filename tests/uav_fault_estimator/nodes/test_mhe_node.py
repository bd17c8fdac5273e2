"""sim_node, residual_node and mhe_node as processes: a fault estimate for every residual,
and in calm air a seeded 10 % lift loss recovered by the estimator's defaults."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest
from uav_common.channels import PAPER_FAULT_NAMES
from uav_common.message_fields import stamp_seconds
from uav_common.ros.node_tools import STREAM_QOS
from uav_common.ros_processes import fast_flight_ros_args, ros2_run_argv
from uav_fault_msgs.msg import FaultEstimate, Residuals

pytestmark = pytest.mark.integration

DURATION_S = 40.0
PERIOD_S = 0.5
CALM = {"north_mps": 0.0, "east_mps": 0.0, "down_mps": 0.0, "turbulence": "none",
        "filter_time_constant_s": 10}
LIFT_LOSS = {"name": "right_wing_lift_loss", "start_s": 0, "ramp_s": 0, "magnitude_pct": 10}


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_estimates_follow_the_residuals_and_find_a_lift_loss(short_scenario, graph,
                                                             start_process):
    received = graph.subscribe({"/faults/estimate": FaultEstimate}, STREAM_QOS)
    estimates = received["/faults/estimate"]
    start_process(ros2_run_argv("uav_fault_estimator", "mhe_node"), "mhe_node")
    assert graph.wait_for_publishers("/faults/estimate", 1, timeout_s=30)
    start_process(ros2_run_argv("uav_fault_estimator", "residual_node"), "residual_node")
    # residual_node's publisher known in the graph (mhe_node matches it about when this
    # node does) before the flight starts: else the first residuals may find no subscriber
    graph.subscribe({"/residuals": Residuals}, STREAM_QOS)
    assert graph.wait_for_publishers("/residuals", 1, timeout_s=30)
    graph.spin(1.0)
    scenario = short_scenario(DURATION_S, wind=CALM, faults=[LIFT_LOSS])
    sim = start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=fast_flight_ros_args(
        scenario, subscribers=1)), "sim_node")
    assert sim.wait(timeout_s=90) == 0, sim.output()
    expected = round(DURATION_S / PERIOD_S)
    graph.spin(60.0, until=lambda: len(estimates) >= expected)

    stamps = [stamp_seconds(message.header.stamp) for message in estimates]
    assert stamps == pytest.approx([PERIOD_S * k for k in range(1, expected + 1)], abs=1e-9)
    statuses = [message.solver_status for message in estimates]
    waiting = sum(status == FaultEstimate.STATUS_WAITING for status in statuses)
    solved = sum(status == FaultEstimate.STATUS_SOLVED for status in statuses)
    final = estimates[-1]
    print(f"{len(estimates)} estimates: {waiting} waiting for valid residuals, {solved} solved;"
          f" final {dict(zip(final.names, np.round(final.values_pct, 2), strict=True))}")
    assert waiting + solved == expected and solved > 0
    for message in estimates:
        assert list(message.names) == list(PAPER_FAULT_NAMES)
        assert len(message.window_values_pct) == message.horizon * len(PAPER_FAULT_NAMES)
    values = dict(zip(final.names, final.values_pct, strict=True))
    assert values["right_wing_lift_loss"] == pytest.approx(10.0, abs=1.0)
    others = [value for name, value in values.items() if name != "right_wing_lift_loss"]
    assert max(others) < 1.0


@pytest.mark.timeout(60)
def test_a_bad_fault_model_ends_mhe_node_with_one_message():
    result = subprocess.run(
        ros2_run_argv("uav_fault_estimator", "mhe_node", ros_args=[
            "-p", "fault_models:=[monotonic, monotonic, gaussian_mixture, monotonic]"]),
        capture_output=True, text=True, timeout=50,
    )
    assert result.returncode == 2  # bad input
    assert "Traceback" not in result.stderr
    assert "mhe_node: fault left_wing_lift_loss: unknown model 'gaussian_mixture'" in (
        result.stderr)
