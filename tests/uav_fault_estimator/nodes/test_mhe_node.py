"""sim_node, residual_node and mhe_node as processes: a fault estimate for every residual,
and in calm air a seeded 10 % lift loss recovered by the estimator's defaults."""

from __future__ import annotations

import signal
import subprocess

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from helpers.diagnostics import latest_values
from rclpy.event_handler import PublisherEventCallbacks
from uav_common.channels import PAPER_FAULT_NAMES
from uav_common.message_fields import stamp_seconds
from uav_common.ros.messages import BODY_FRAME, header
from uav_common.ros.qos import DIAGNOSTICS_QOS, STREAM_QOS
from uav_common.ros_processes import fast_flight_ros_args, ros2_run_argv
from uav_fault_estimator.estimation.noise_model import load_noise_calibration
from uav_fault_msgs.msg import FaultEstimate, Residuals

pytestmark = pytest.mark.integration

DURATION_S = 40.0
PERIOD_S = 0.5
TAU_A_S = 4.0  # the residuals' F_a, as residual_node's default sends it [s]
CALM = {"north_mps": 0.0, "east_mps": 0.0, "down_mps": 0.0, "turbulence": "none",
        "filter_time_constant_s": 10}
LIFT_LOSS = {"name": "right_wing_lift_loss", "start_s": 0, "ramp_s": 0, "magnitude_pct": 10}


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_estimates_follow_the_residuals_and_find_a_lift_loss(short_scenario, graph,
                                                             start_process):
    received = graph.subscribe({"/faults/estimate": FaultEstimate}, STREAM_QOS)
    estimates = received["/faults/estimate"]
    # each node subscribes to its inputs once its output is matched: residual_node's with
    # mhe_node, mhe_node's with this test; sim_node flies once residual_node listens
    mhe = start_process(ros2_run_argv("uav_fault_estimator", "mhe_node",
                                      ros_args=["-p", "wait_for_subscribers:=1"]), "mhe_node")
    start_process(ros2_run_argv("uav_fault_estimator", "residual_node",
                                ros_args=["-p", "wait_for_subscribers:=1"]), "residual_node")
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
    # said once at start, so that a flight in real time does not look stuck
    assert mhe.output().count("the estimates are the prior (0, 0, 0, 0 %) until the "
                              "residuals are valid") == 1, mhe.output()


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


@pytest.mark.timeout(60)
def test_an_unknown_fault_name_ends_mhe_node_with_one_message():
    names = "[right_wing_lift_loss, right_wing_drag_increase, bogus_fault, left_wing_drag_increase]"
    result = subprocess.run(
        ros2_run_argv("uav_fault_estimator", "mhe_node", ros_args=["-p", f"fault_names:={names}"]),
        capture_output=True, text=True, timeout=50,
    )
    assert result.returncode == 2  # bad input
    assert "Traceback" not in result.stderr
    lines = [line for line in result.stderr.splitlines() if "bogus_fault" in line]
    print(lines)
    assert len(lines) == 1 and "right_wing_lift_loss" in lines[0]


class SyntheticResiduals:
    """Residuals y = S f + noise of a 5 % right-wing lift loss (air data flown, S of about
    two noise deviations per %, seeded), published straight to mhe_node by the test's
    graph node, which also watches the estimates and /diagnostics."""

    def __init__(self, graph, seed: int) -> None:
        self.noise_sd = np.sqrt(load_noise_calibration().variances["air_data"])
        self.rng = np.random.default_rng(seed)
        self.sensitivity = 2.0 * self.noise_sd[:, None] * self.rng.normal(
            size=(Residuals.CHANNELS, 4))
        self.estimates = graph.subscribe({"/faults/estimate": FaultEstimate},
                                         STREAM_QOS)["/faults/estimate"]
        self.diagnostics = graph.subscribe({"/diagnostics": DiagnosticArray},
                                           DIAGNOSTICS_QOS)["/diagnostics"]
        self.graph = graph
        self.matched_total = 0  # subscriptions ever matched with the publisher
        self.publisher = graph.node.create_publisher(
            Residuals, "/residuals", STREAM_QOS,
            event_callbacks=PublisherEventCallbacks(matched=self._on_matched))

    def _on_matched(self, info) -> None:
        self.matched_total = info.total_count

    def start_mhe_node(self, start_process, name: str, ros_args: tuple[str, ...] = ()):
        """mhe_node as a process, once it listens to this publisher: it subscribes once its
        estimates are matched with this test's subscription, and the publisher counts a new
        match (not a killed node's subscription, which may still count for a while)."""
        before = self.matched_total
        node = start_process(ros2_run_argv("uav_fault_estimator", "mhe_node", ros_args=[
            "-p", "wait_for_subscribers:=1", *ros_args]), name)
        assert self.graph.wait(f"{name} subscribed to this test's /residuals",
                               lambda: self.matched_total > before, timeout_s=30), node.output()
        return node

    def message(self, k: int, faults_pct: tuple[float, ...] = (5.0, 0.0, 0.0, 0.0)
                ) -> Residuals:
        """The k-th residual, stamped k · PERIOD_S."""
        residual = (self.sensitivity @ np.array(faults_pct)
                    + self.noise_sd * self.rng.normal(size=Residuals.CHANNELS))
        return Residuals(header=header(k * PERIOD_S, BODY_FRAME), residual=residual.tolist(),
                         valid=[True] * Residuals.CHANNELS,
                         wind_source=Residuals.WIND_AIR_DATA,
                         filter_time_constant_s=TAU_A_S,
                         fault_names=list(PAPER_FAULT_NAMES),
                         sensitivity=self.sensitivity.ravel().tolist())

    def node_values(self) -> dict[str, str]:
        """The values of mhe_node's last status on /diagnostics, once it counts an update for
        every estimate received (it is published once a second)."""
        assert self.graph.wait(
            f"mhe_node's /diagnostics counting {len(self.estimates)} updates",
            lambda: latest_values(self.diagnostics, "/mhe_node").get("updates")
            == str(len(self.estimates)), timeout_s=10)
        return latest_values(self.diagnostics, "/mhe_node")


@pytest.mark.timeout(120)
def test_hostile_residuals_are_one_dropped_message_each_and_the_estimates_go_on(
        graph, start_process):
    """Published straight to mhe_node among 60 good residuals of a 5 % lift loss: one with a
    wind_source outside the message's enum (an exception in the noise model before) and one
    with S = 1e300 (seconds of solver time before). The first is dropped and counted on
    /diagnostics, the second is INVALID_DATA with the last good estimate; the node keeps
    running and ends at the lift loss."""
    synthetic = SyntheticResiduals(graph, seed=3)
    estimates = synthetic.estimates
    node = synthetic.start_mhe_node(start_process, "mhe_node")
    bad_source, huge_s, count = 20, 30, 60
    for k in range(1, count + 1):
        message = synthetic.message(k)
        if k == bad_source:
            message.wind_source = 7
        if k == huge_s:
            message.sensitivity[0] = 1e300
        synthetic.publisher.publish(message)
        graph.spin(5.0, until=lambda k=k: len(estimates) >= k - (k >= bad_source))
    graph.spin(2.0)
    assert node.running(), node.output()
    stamps = {round(stamp_seconds(m.header.stamp) / PERIOD_S): m for m in estimates}
    assert sorted(stamps) == [k for k in range(1, count + 1) if k != bad_source]
    assert stamps[huge_s].solver_status == FaultEstimate.STATUS_INVALID_DATA
    assert stamps[huge_s].values_pct == stamps[huge_s - 1].values_pct
    print(f"S = 1e300: {stamps[huge_s].solve_time_ms:.3f} ms; final "
          f"{np.round(estimates[-1].values_pct, 2)} %")
    assert estimates[-1].values_pct[0] == pytest.approx(5.0, abs=1.0)
    assert synthetic.node_values()["rejected_messages"] == "1"


@pytest.mark.timeout(120)
def test_an_air_data_loss_holds_the_estimate_until_f_a_has_settled(graph, start_process):
    """Residuals that flew the filtered wind after the air data (a loss of 5 s) and the
    air-data ones for 3 tau_a after it (tau_a the residuals' own filter_time_constant_s):
    HELD, with the estimate before the loss, counted on /diagnostics; then estimated again."""
    synthetic = SyntheticResiduals(graph, seed=5)
    estimates = synthetic.estimates
    node = synthetic.start_mhe_node(start_process, "mhe_node")
    lost, count = range(41, 51), 90
    for k in range(1, count + 1):
        message = synthetic.message(k)
        if k in lost:
            message.wind_source = Residuals.WIND_FILTERED
        synthetic.publisher.publish(message)
        graph.spin(5.0, until=lambda k=k: len(estimates) >= k)
    graph.spin(2.0)
    assert node.running(), node.output()
    statuses = [m.solver_status for m in estimates]
    held = [k for k, status in enumerate(statuses, start=1)
            if status == FaultEstimate.STATUS_HELD]
    assert held == [k for k in range(lost.start, count + 1)  # held less than 3 tau_a after
                    if (k - lost[-1]) * PERIOD_S < 3 * TAU_A_S]
    assert all(estimates[k - 1].values_pct == estimates[39].values_pct for k in held)
    assert statuses[-1] == FaultEstimate.STATUS_SOLVED
    assert estimates[-1].values_pct[0] == pytest.approx(5.0, abs=1.0)
    assert synthetic.node_values()["held"] == str(len(held))


@pytest.mark.timeout(120)
def test_a_gap_in_the_residuals_keeps_the_diagnosis(graph, start_process):
    """A residual source silent for 20 s (residual_node killed and started again, the
    flight going on): mhe_node bridges the gap instead of resetting, the estimate across it
    stays the one before it (a 5 % lift loss; a reset would start it from 0 again), and
    every residual sent gets its estimate."""
    synthetic = SyntheticResiduals(graph, seed=4)
    estimates = synthetic.estimates
    node = synthetic.start_mhe_node(start_process, "mhe_node")
    sent = [*range(1, 41), *range(81, 121)]  # 0.5-20 s, then 40.5-60 s
    for count, k in enumerate(sent, start=1):
        synthetic.publisher.publish(synthetic.message(k))
        graph.spin(5.0, until=lambda count=count: len(estimates) >= count)
    graph.spin(2.0)
    assert node.running(), node.output()
    stamps = {round(stamp_seconds(m.header.stamp) / PERIOD_S): m for m in estimates}
    assert sorted(stamps) == sent
    before, after = stamps[40].values_pct, stamps[81].values_pct
    print(f"before the gap {np.round(before, 2)} %, after it {np.round(after, 2)} %")
    assert after == pytest.approx(before, abs=0.5)
    assert stamps[120].values_pct[0] == pytest.approx(5.0, abs=1.0)
    values = synthetic.node_values()
    assert values["stamp_resets"] == "0" and values["gaps"] == "1"
    assert "resumed at 40.500 s after a gap of 20.50 s" in node.output()


@pytest.mark.timeout(120)
def test_a_restarted_mhe_node_starts_from_its_last_estimate(graph, start_process, tmp_path):
    """mhe_node with a state file killed (SIGKILL) after 10 s of a 5 % lift loss and
    started again: its first estimate is the one it had, not the prior (0 %); a flight
    that starts again (stamps from 0.5 s, fault-free) starts from the prior, and says so."""
    synthetic = SyntheticResiduals(graph, seed=5)
    estimates = synthetic.estimates
    state_file = ("-p", f"state_file:={tmp_path / 'mhe.json'}")


    def fly(name: str, steps: range, faults_pct: tuple[float, ...] = (5.0, 0.0, 0.0, 0.0)
            ) -> tuple[list[FaultEstimate], str]:
        """Start the node, send the residuals, kill it; its estimates and its log."""
        node = synthetic.start_mhe_node(start_process, name, state_file)
        estimates.clear()
        for count, k in enumerate(steps, start=1):
            synthetic.publisher.publish(synthetic.message(k, faults_pct))
            graph.spin(5.0, until=lambda count=count: len(estimates) >= count)
        assert len(estimates) == len(steps), node.output()
        node.stop(signal.SIGKILL)
        return list(estimates), node.output()

    first, _ = fly("mhe_node", range(1, 21))
    resumed, log = fly("mhe_node_again", range(21, 31))
    print(f"last before {np.round(first[-1].values_pct, 2)}, first after "
          f"{np.round(resumed[0].values_pct, 2)} %")
    assert "resumed from" in log  # the last estimate it had saved: of 9.5 or 10 s
    assert resumed[0].values_pct == pytest.approx(first[-1].values_pct, abs=0.5)
    again, log = fly("mhe_node_new_flight", range(1, 5), (0.0, 0.0, 0.0, 0.0))  # fault-free
    assert "a new flight, starting from the prior" in log
    assert max(again[0].values_pct) < 1.0
