"""mhe_node: moving-horizon MAP fault estimates from the residual stream.

Subscribes `residuals` (Residuals); publishes `faults/estimate` (FaultEstimate) on every
residual, stamped with the residual's stamp, and solver figures on `/diagnostics`, with the
model's health as a status of its own, `mhe_node/model_fit` (estimation/model_fit.py). With
estimate_wind_errors it publishes `air_data/estimate` (AirDataEstimate) on every solved
residual whose models flew a pitot without vanes: synthetic flow angles and wind
(estimation/air_data_estimate.py).
"""

from __future__ import annotations

import sys
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np
from rclpy.node import Node
from std_msgs.msg import Header
from uav_common.message_fields import stamp_nanoseconds, stamp_seconds
from uav_common.ros.diagnostics import ERROR, OK, WARN, Diagnostics
from uav_common.ros.matched_streams import guarded
from uav_common.ros.messages import BODY_FRAME, header
from uav_common.ros.node_life import run_node, when_subscribed
from uav_common.ros.parameters import (
    QOS_PARAMETER,
    WAIT_FOR_SUBSCRIBERS_PARAMETER,
    ParameterError,
    ParameterSpec,
    declare_parameters,
)
from uav_common.ros.qos import STREAM_QOS_PROFILES
from uav_common.settings import parameter_specs, replaced, settings_from
from uav_common.stamp_matching import GuardedStream, StampVerdict
from uav_fault_msgs.msg import AirDataEstimate as AirDataEstimateMessage
from uav_fault_msgs.msg import FaultEstimate, Residuals

from uav_fault_estimator.estimation.air_data_estimate import AirDataEstimate
from uav_fault_estimator.estimation.estimator_config import SOLVER_METHOD_KEY, SOLVER_METHODS
from uav_fault_estimator.estimation.estimator_settings import EstimatorSettings
from uav_fault_estimator.estimation.estimator_step import (
    EstimatorStep,
    RejectedSampleError,
    ResidualInput,
    StepResult,
    warm_up_text,
)
from uav_fault_estimator.estimation.mhe import EstimateResult
from uav_fault_estimator.estimation.model_fit import DOES_NOT_FIT, FitVerdict
from uav_fault_estimator.estimation.saved_estimate import (
    SavedEstimate,
    load_estimate,
    resumed_prior,
    save_estimate,
)
from uav_fault_estimator.estimation.solve_status import SolveStatus

# The core's settings (EstimatorSettings), then the node's own.
PARAMETERS = {
    **parameter_specs(EstimatorSettings),
    "state_file": ParameterSpec(
        "file for the last estimate: a restart within the flight (a first residual later "
        "than the saved one) starts from it; empty: none", ""),
    "qos": QOS_PARAMETER,
    "wait_for_subscribers": WAIT_FOR_SUBSCRIBERS_PARAMETER,
}
RECENT_SOLVES = 200  # solve times kept for the median and p99 on /diagnostics


class MheNode(Node):
    """Thin adapter: Residuals in, one estimator update each, FaultEstimate out."""

    def __init__(self) -> None:
        super().__init__("mhe_node")
        p = declare_parameters(self, PARAMETERS, self.retune)
        self.step = EstimatorStep(settings_from(EstimatorSettings, p))
        self.names = self.step.published_names
        self.estimated = self.step.estimated_names  # faults, then any nuisance parameters
        qos = STREAM_QOS_PROFILES[p["qos"]]
        self.publisher = self.create_publisher(FaultEstimate, "faults/estimate", qos)
        self.air_data_publisher = (
            self.create_publisher(AirDataEstimateMessage, "air_data/estimate", qos)
            if p["estimate_wind_errors"] else None)
        when_subscribed(self, self.publisher, p["wait_for_subscribers"],
                        lambda: self.create_subscription(
                            Residuals, "residuals", self.on_residuals, qos))
        self.diagnostics = Diagnostics(self)
        self.update_times_ms: deque[float] = deque(maxlen=RECENT_SOLVES)
        self.counts = {"updates": 0, "solves": 0, "not_solved": 0, "rejected_messages": 0,
                       "stamp_resets": 0, "gaps": 0, "held": 0,
                       **{f"solved_by_{method}": 0 for method in SOLVER_METHODS}}
        self.stamps = GuardedStream()
        self.state_file = Path(p["state_file"]) if p["state_file"] else None
        self.saved = self.saved_estimate()
        self.get_logger().info(warm_up_text(self.step.config))

    def retune(self, changes: dict[str, Any]) -> None:
        """Apply changed live parameters from the next residual on (ParameterError: none)."""
        try:
            self.step.retune(replaced(self.step.settings, changes))
        except ValueError as error:
            raise ParameterError(str(error)) from None
        self.get_logger().info("retuned: " + ", ".join(
            f"{name} = {value}" for name, value in changes.items()))

    def on_residuals(self, message: Residuals) -> None:
        """Guard the stamp (a stray dropped, a gap bridged, a restart of the flight reset),
        then one estimator update per residual taken."""
        verdict, taken = guarded(self, self.stamps, "residuals",
                                 stamp_nanoseconds(message.header.stamp), message,
                                 "estimator reset")
        if verdict is StampVerdict.RESTART:
            self.step.reset()
            self.counts["stamp_resets"] += 1
        if verdict is StampVerdict.GAP:
            self.counts["gaps"] += 1
            self.step.bridge(self.stamps.guard.last_gap_ns / 1e9)
        for stamp_ns, residuals in taken:
            self.resume(stamp_ns)
            self.estimate(residuals)

    def saved_estimate(self) -> SavedEstimate | None:
        """The state file's estimate, if there is one for these faults (else said, once)."""
        if self.state_file is None:
            return None
        try:
            saved = load_estimate(self.state_file)
        except ValueError as error:
            self.get_logger().warning(f"{error}: starting from the prior")
            return None
        if saved is not None and list(saved.names) != self.names:
            self.get_logger().warning(f"state file {self.state_file} holds {list(saved.names)}, "
                                      "not this node's faults: starting from the prior")
            return None
        return saved

    def resume(self, stamp_ns: int) -> None:
        """Before the first residual: start from the saved estimate if the flight has gone
        on since it (the residual is later), else it is another flight's: the prior."""
        saved, self.saved = self.saved, None
        if saved is None:
            return
        prior = resumed_prior(saved, stamp_ns, self.step.config.prior_pct, self.estimated)
        if prior is None:
            self.get_logger().warning(
                f"state file {self.state_file} is of {saved.stamp_ns / 1e9:.3f} s, the first "
                f"residual of {stamp_ns / 1e9:.3f} s: a new flight, starting from the prior")
            return
        self.step.reset(prior)
        self.counts["resumed_from_s"] = round(saved.stamp_ns / 1e9, 3)
        self.get_logger().info(
            f"resumed from {self.state_file}: the estimate of {saved.stamp_ns / 1e9:.3f} s, "
            + ", ".join(f"{n} {v:.2f} %" for n, v in zip(saved.names, saved.values_pct,
                                                        strict=True)))

    def estimate(self, message: Residuals) -> None:
        """One estimator step with the residual, its estimate published."""
        try:
            step = self.step.update(ResidualInput(
                stamp_seconds(message.header.stamp), np.array(message.residual),
                np.array(message.valid), np.array(message.sensitivity),
                message.fault_names, message.wind_source, message.filter_time_constant_s,
                np.array(message.wind_flown_ned_mps), np.array(message.air_velocity_body_mps),
                np.array(message.attitude_rad)))
        except RejectedSampleError as error:
            self.reject(str(error))
            return
        estimate = self.estimate_message(message, step)
        self.publisher.publish(estimate)
        if step.air_data is not None and self.air_data_publisher is not None:
            self.air_data_publisher.publish(air_data_message(estimate.header, step.air_data))
        self.count(step.estimate)
        self.report_fit(step.fit)
        if self.state_file is not None:
            self.save(SavedEstimate(stamp_nanoseconds(message.header.stamp), tuple(self.names),
                                    tuple(estimate.values_pct)))

    def report_fit(self, verdict: FitVerdict) -> None:
        """The model_fit status on /diagnostics."""
        self.diagnostics.update_part(
            "model_fit", WARN if verdict.verdict == DOES_NOT_FIT else OK, verdict.text,
            {"verdict": verdict.verdict, "largest_mean_sigmas": f"{verdict.largest_sigmas:.2f}",
             "channel": verdict.channel, "window_samples": verdict.samples})

    def save(self, estimate: SavedEstimate) -> None:
        """Keep the estimate in the state file; a file that cannot be written is said once
        and not tried again."""
        try:
            save_estimate(self.state_file, estimate)
        except OSError as error:
            self.get_logger().error(f"state file {self.state_file}: {error}; not kept")
            self.state_file = None

    def reject(self, reason: str) -> None:
        """A residual the step cannot use: dropped, counted and said."""
        self.counts["rejected_messages"] += 1
        self.get_logger().warning(f"residuals skipped: {reason}", throttle_duration_sec=5.0)
        self.diagnostics.update(ERROR, f"residuals skipped: {reason}", self.health())

    def estimate_message(self, message: Residuals, step: StepResult) -> FaultEstimate:
        result = step.estimate
        return FaultEstimate(
            header=header(stamp_seconds(message.header.stamp), BODY_FRAME),
            names=self.names,
            values_pct=step.published_pct.tolist(),
            solver_status=int(result.status),
            updated=result.status is SolveStatus.SOLVED,
            horizon=self.step.config.horizon,
            horizon_s=step.horizon_s,
            window_values_pct=step.window_pct.ravel().tolist(),  # row-major N x n
            iterations=result.iterations,
            solve_time_ms=result.update_time_ms,
            update_cpu_time_ms=result.update_cpu_ms,
        )

    def health(self) -> dict[str, Any]:
        """The counters /diagnostics shows, the stamp guard's strays among them."""
        return {**self.counts, "stray_stamps": self.stamps.strays,
                "budget_overruns": self.step.estimator.overruns,
                "dropped_suspects": self.step.estimator.dropped_suspects}

    def count(self, result: EstimateResult) -> None:
        """Counters and solve times for /diagnostics."""
        self.counts["updates"] += 1
        if result.status is SolveStatus.WAITING:
            level, text = OK, "waiting for valid residuals"
        elif result.status is SolveStatus.HELD:
            self.counts["held"] += 1
            level, text = WARN, "air data lost or settling: estimate held"
        elif result.status is SolveStatus.SOLVED:
            self.counts["solves"] += 1
            self.counts[f"solved_by_{result.solved_by}"] += 1
            self.update_times_ms.append(result.update_time_ms)
            level, text = OK, "estimating"
        else:
            self.counts["not_solved"] += 1
            level, text = WARN, f"{result.status.name.lower()}: last good estimate kept"
        times = np.array(self.update_times_ms) if self.update_times_ms else np.zeros(1)
        nuisance = {name: value for name, value in
                    zip(self.estimated, result.fault_pct, strict=True) if name not in self.names}
        self.diagnostics.update(level, text, {
            SOLVER_METHOD_KEY: self.step.config.solver.method,
            **self.health(),
            **{f"{name}_mps": f"{value:.2f}" for name, value in nuisance.items()},
            "median_ms": f"{np.median(times):.3f}",
            "p99_ms": f"{np.percentile(times, 99):.3f}",
            "max_ms": f"{times.max():.3f}",
        })


def air_data_message(header: Header, air_data: AirDataEstimate) -> AirDataEstimateMessage:
    """The synthetic air data as its message, under the estimate's header."""
    return AirDataEstimateMessage(
        header=header, true_airspeed_mps=air_data.true_airspeed_mps,
        angle_of_attack_rad=air_data.angle_of_attack_rad, sideslip_rad=air_data.sideslip_rad,
        wind_ned_mps=air_data.wind_ned_mps.tolist(),
        angle_of_attack_std_rad=air_data.angle_of_attack_std_rad,
        sideslip_std_rad=air_data.sideslip_std_rad, wind_std_mps=air_data.wind_std_mps.tolist())


def main(args: list[str] | None = None) -> int:
    return run_node("mhe_node", MheNode, args=args)


if __name__ == "__main__":
    sys.exit(main())
