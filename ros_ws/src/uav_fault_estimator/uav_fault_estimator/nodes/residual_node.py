"""residual_node: acceleration residuals and fault sensitivities from the sensor streams.

Subscribes `state`, `controls`, `wind/filtered` and, where the aircraft has it, `air_data`
(matched by stamp); publishes `residuals` (Residuals) every update_period_s of sim time, and
`/diagnostics`. The models fly the air data when a sample has usable air data and the
filtered wind otherwise (residuals.py); a fallback is a WARN on /diagnostics. With a
model_calibration_file (scripts/calibrate_model.py) the models are the calibrated aircraft
and the calibration's air-data bias is taken out of the air data; a file made for another
vehicle, or another version of its XML, is refused at start (one line, exit status 2).
"""

from __future__ import annotations

import sys
import time

from rclpy.node import Node
from uav_aircraft.flown_aircraft import NOMINAL
from uav_common.envelope import (
    AIR_DATA_LIMITS,
    CONTROL_LIMITS,
    STATE_LIMITS,
    WIND_LIMITS,
    state_rate_gate,
)
from uav_common.message_fields import air_data_array, controls_array, state_array, wind_array
from uav_common.ros.diagnostics import OK, WARN, Diagnostics
from uav_common.ros.matched_streams import MatchedStreams
from uav_common.ros.messages import BODY_FRAME, header
from uav_common.ros.node_life import run_node, when_subscribed
from uav_common.ros.parameters import (
    QOS_PARAMETER,
    WAIT_FOR_SUBSCRIBERS_PARAMETER,
    ParameterSpec,
    declare_parameters,
)
from uav_common.ros.qos import STREAM_QOS_PROFILES
from uav_common.settings import parameter_specs, settings_from
from uav_fault_msgs.msg import AircraftState, AirData, ControlInputs, Residuals, WindEstimate

from uav_fault_estimator.estimation.model_file import (
    MODEL_KEY,
    load_model_calibration,
    shipped_model,
)
from uav_fault_estimator.estimation.prediction import residual_sampler
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.estimation.residuals import (
    RESIDUAL_CHANNELS,
    WIND_AIR_DATA,
    WIND_FILTERED,
    WIND_SOURCE_NAMES,
    ResidualSample,
)

# The core's settings (ResidualSettings), then the node's own.
PARAMETERS = {
    **parameter_specs(ResidualSettings),
    "model_calibration_file": ParameterSpec(
        "model calibration YAML (scripts/calibrate_model.py); empty: the vehicle's XML as "
        "shipped", ""),
    "qos": QOS_PARAMETER,
    "wait_for_subscribers": WAIT_FOR_SUBSCRIBERS_PARAMETER,
}
# `state` last: see MatchedStreams
STREAMS = {"controls": (ControlInputs, controls_array, CONTROL_LIMITS, None),
           "wind/filtered": (WindEstimate, wind_array, WIND_LIMITS, None),
           "state": (AircraftState, state_array, STATE_LIMITS, state_rate_gate)}
OPTIONAL_STREAMS = {"air_data": (AirData, air_data_array, AIR_DATA_LIMITS, None)}


class ResidualNode(Node):
    """Thin adapter: messages matched by stamp, one core update per sample, publication."""

    def __init__(self) -> None:
        super().__init__("residual_node")
        p = declare_parameters(self, PARAMETERS)
        settings = settings_from(ResidualSettings, p)
        calibration = p["model_calibration_file"]
        self.model = calibration or shipped_model(settings.vehicle)
        self.sampler = residual_sampler(
            settings, load_model_calibration(calibration, settings.vehicle).aircraft
            if calibration else NOMINAL)
        self.generator = self.sampler.generator
        qos = STREAM_QOS_PROFILES[p["qos"]]
        self.publisher = self.create_publisher(Residuals, "residuals", qos)
        self.streams = MatchedStreams(self, STREAMS, self.process, self.restart, "filters reset",
                                      qos, OPTIONAL_STREAMS)
        when_subscribed(self, self.publisher, p["wait_for_subscribers"], self.streams.subscribe)
        self.diagnostics = Diagnostics(self)
        self.counts = {"samples": 0, "published": 0, "rejected_samples": 0,
                       "filtered_wind_samples": 0}
        self.core_time_s = 0.0

    def restart(self) -> None:
        """The source restarted: the filters from scratch."""
        self.sampler.reset()

    def process(self, time_s: float, payloads: dict) -> None:
        """One core update; publishes when the update period is due."""
        started = time.perf_counter()
        try:
            sample = self.sampler.update(
                time_s, payloads["state"], payloads["controls"], payloads["wind/filtered"],
                payloads.get("air_data"))
        except ValueError as error:  # a sample the model cannot evaluate: skipped
            self.counts["rejected_samples"] += 1
            self.get_logger().warning(f"sample at {time_s:.3f} s skipped: {error}")
            self.diagnostics.update(WARN, f"sample skipped: {error}", self.health())
            return
        finally:
            self.core_time_s += time.perf_counter() - started
        self.counts["samples"] += 1
        newest = self.sampler.newest
        if newest is not None and newest.wind_source == WIND_FILTERED:
            self.counts["filtered_wind_samples"] += 1
        if sample is None:
            return
        self.publisher.publish(self.message(sample))
        self.counts["published"] += 1
        self.report(sample)

    def message(self, sample: ResidualSample) -> Residuals:
        return Residuals(
            header=header(sample.time_s, BODY_FRAME),
            residual=sample.residual.tolist(),
            observed=sample.observed.tolist(),
            predicted=sample.predicted.tolist(),
            valid=sample.valid.tolist(),
            wind_source=sample.wind_source,
            filter_time_constant_s=sample.tau_a_s,
            wind_flown_ned_mps=sample.wind_flown_ned_mps.tolist(),
            air_velocity_body_mps=sample.air_velocity_body_mps.tolist(),
            attitude_rad=sample.attitude_rad.tolist(),
            fault_names=list(self.generator.column_names),
            sensitivity=sample.sensitivity.ravel().tolist(),  # row-major 6 x p
        )

    def health(self) -> dict[str, object]:
        """Counters and cost for /diagnostics."""
        return {
            **self.counts,
            "stamp_resets": self.streams.restarts,
            "stray_stamps": self.streams.stray_messages,
            "dropped_incomplete_samples": self.streams.dropped_sets,
            "late_optional_messages": self.streams.late_optional,
            "implausible_values": self.streams.implausible_values,
            "model_rebuilds": self.generator.model_rebuilds,
            MODEL_KEY: self.model,
            "core_ms_per_sample": f"{1e3 * self.core_time_s / max(self.counts['samples'], 1):.3f}",
        }

    def report(self, sample: ResidualSample) -> None:
        invalid = [name for name, ok in zip(RESIDUAL_CHANNELS, sample.valid, strict=True)
                   if not ok]
        source = WIND_SOURCE_NAMES[sample.wind_source]
        problems = []
        if invalid:
            problems.append("rows invalid (a state channel is missing or implausible): "
                            + ", ".join(invalid))
        if sample.wind_source != WIND_AIR_DATA and self.streams.has_publisher("air_data"):
            problems.append("no usable air data: the models fly the filtered wind"
                            if sample.wind_source == WIND_FILTERED else
                            "no usable flow angles: the models fly the pitot without vanes")
        self.diagnostics.update(
            WARN if problems else OK, "; ".join(problems) or f"residuals valid ({source})",
            {**self.health(), "invalid_rows": ",".join(invalid) or "none",
             "wind_source": source},
        )

def main(args: list[str] | None = None) -> int:
    return run_node("residual_node", ResidualNode, args=args)


if __name__ == "__main__":
    sys.exit(main())
