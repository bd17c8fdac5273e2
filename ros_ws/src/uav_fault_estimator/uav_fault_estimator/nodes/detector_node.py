"""detector_node: fast fault alarms from self-tuning residual generators.

Subscribes `state` and `controls` (matched by stamp), and where they come `air_data` (its
airspeed, for a calibration scheduled on airspeed) and `autopilot_setpoints` (for the
tracking generators); on the calibration's sample grid (every 0.2 s of sim time) runs the
calibration's RLS residual generators, their GLRT and the parameter-deviation test
(detection/; Blanke & Hansen) and beside them the fast window test on the residuals with the
calibration's parameters, with the forgetting factor, windows and settling time the
calibration was made with, and publishes `faults/alarm` (FaultAlarm, stamped like the
sample), and `/diagnostics`.
"""

from __future__ import annotations

import math
import sys
from typing import Any

from rclpy.node import Node
from uav_common.envelope import (
    AIR_DATA_LIMITS,
    CONTROL_LIMITS,
    SETPOINT_LIMITS,
    STATE_LIMITS,
    state_rate_gate,
)
from uav_common.message_fields import (
    air_data_array,
    controls_array,
    setpoints_array,
    state_array,
)
from uav_common.ros.diagnostics import ERROR, OK, WARN, Diagnostics
from uav_common.ros.matched_streams import MatchedStreams
from uav_common.ros.messages import BODY_FRAME, header
from uav_common.ros.node_life import run_node, when_subscribed
from uav_common.ros.parameters import (
    QOS_PARAMETER,
    WAIT_FOR_SUBSCRIBERS_PARAMETER,
    declare_parameters,
)
from uav_common.ros.qos import STREAM_QOS_PROFILES
from uav_common.settings import parameter_specs, settings_from
from uav_fault_msgs.msg import (
    AircraftState,
    AirData,
    AutopilotSetpoints,
    ControlInputs,
    FaultAlarm,
)

from uav_fault_estimator.detection.detector import DetectorSample
from uav_fault_estimator.detection.detector_settings import (
    DetectorSettings,
    self_tuning_detector,
)
from uav_fault_estimator.detection.generators import NO_SETPOINTS

# The core's settings (DetectorSettings), then the node's own.
PARAMETERS = {
    **parameter_specs(DetectorSettings),
    "qos": QOS_PARAMETER,
    "wait_for_subscribers": WAIT_FOR_SUBSCRIBERS_PARAMETER,
}
# `state` last: see MatchedStreams
STREAMS = {"controls": (ControlInputs, controls_array, CONTROL_LIMITS, None),
           "state": (AircraftState, state_array, STATE_LIMITS, state_rate_gate)}
OPTIONAL_STREAMS = {"air_data": (AirData, air_data_array, AIR_DATA_LIMITS, None),
                    "autopilot_setpoints": (AutopilotSetpoints, setpoints_array,
                                            SETPOINT_LIMITS, None)}
_AIRSPEED = 0  # air_data_array's index of the true airspeed


class DetectorNode(Node):
    """Thin adapter: messages matched by stamp, one core update per sample, publication."""

    def __init__(self) -> None:
        super().__init__("detector_node")
        p = declare_parameters(self, PARAMETERS, self.retune)
        self.detector = self_tuning_detector(settings_from(DetectorSettings, p))
        templates = self.detector.templates
        self.template_kinds = () if templates is None else templates.kinds
        qos = STREAM_QOS_PROFILES[p["qos"]]
        self.publisher = self.create_publisher(FaultAlarm, "faults/alarm", qos)
        self.streams = MatchedStreams(self, STREAMS, self.process, self.detector.reset,
                                      "generators reset to the calibration", qos,
                                      optional=OPTIONAL_STREAMS)
        when_subscribed(self, self.publisher, p["wait_for_subscribers"], self.streams.subscribe)
        self.diagnostics = Diagnostics(self)
        self.counts = {"published": 0, "combined_alarms": 0}

    def retune(self, changes: dict[str, Any]) -> None:
        """The thresholds for a changed false-alarm probability or fast-test or template-test
        rate, from the next sample on."""
        if "false_alarm_probability" in changes:
            self.detector.set_false_alarm_probability(changes["false_alarm_probability"])
            self.get_logger().info(
                f"thresholds for P_FA = {changes['false_alarm_probability']:g}")
        if "fast_false_alarms_per_hour" in changes:
            self.detector.set_fast_false_alarm_rate(changes["fast_false_alarms_per_hour"])
            self.get_logger().info("fast-test thresholds for "
                                   f"{changes['fast_false_alarms_per_hour']:g} per hour")
        if "template_false_alarms_per_hour" in changes:
            rate = changes["template_false_alarms_per_hour"]
            self.detector.set_template_false_alarm_rate(rate)
            self.get_logger().info(f"template-test thresholds for {rate:g} per hour")

    def process(self, time_s: float, payloads: dict) -> None:
        skipped = self.detector.skipped_samples
        air_data = payloads.get("air_data")
        sample = self.detector.update(time_s, payloads["state"], payloads["controls"],
                                      math.nan if air_data is None else air_data[_AIRSPEED],
                                      payloads.get("autopilot_setpoints", NO_SETPOINTS))
        if sample is None:  # off the grid, or skipped
            if self.detector.skipped_samples > skipped:
                self.diagnostics.update(WARN, "sample skipped (first, or a value a generator "
                                        "takes missing or implausible)", self.health())
            return
        self.publisher.publish(self.message(sample))
        self.counts["published"] += 1
        self.counts["combined_alarms"] += int(sample.combined_alarm)
        self.report(sample)

    def message(self, sample: DetectorSample) -> FaultAlarm:
        return FaultAlarm(
            header=header(sample.time_s, BODY_FRAME),
            channel_names=list(self.detector.calibration.channel_names),
            statistic=sample.statistic.tolist(),
            threshold=sample.threshold.tolist(),
            alarm=sample.alarm.tolist(),
            parameter_deviation=sample.parameter_deviation.tolist(),
            parameter_threshold=sample.parameter_threshold,
            parameter_alarm=sample.parameter_alarm,
            fast_statistic=sample.fast_statistic.tolist(),
            fast_threshold=sample.fast_threshold.tolist(),
            fast_alarm=sample.fast_alarm.tolist(),
            template_kinds=list(self.template_kinds),
            template_statistic=sample.template_statistic.tolist(),
            template_threshold=sample.template_threshold.tolist(),
            template_alarm=sample.template_alarm.tolist(),
            combined_alarm=sample.combined_alarm,
            false_alarm_probability=self.detector.false_alarm_probability,
            fast_false_alarms_per_hour=self.detector.fast_false_alarms_per_hour,
            template_false_alarms_per_hour=self.detector.template_false_alarms_per_hour,
            cause=sample.cause,
        )

    def report(self, sample: DetectorSample) -> None:
        names = self.detector.calibration.channel_names
        alarms = [name for name, on in zip(names, sample.alarm, strict=True) if on]
        fast = [name for name, on in zip(names, sample.fast_alarm, strict=True) if on]
        shapes = [kind for kind, on in zip(self.template_kinds, sample.template_alarm,
                                           strict=True) if on]
        if sample.combined_alarm:
            level, text = ERROR, f"fault ({sample.cause or 'kind unknown'}): " + "; ".join(
                (["GLRT and parameters agree"] if sample.self_tuning_alarm else [])
                + ([f"fast test on {', '.join(fast)}"] if fast else [])
                + ([f"shape of {', '.join(shapes)}"] if shapes else []))
        elif alarms or sample.parameter_alarm:
            level, text = WARN, "one test alarms: " + ", ".join(
                alarms + (["parameters"] if sample.parameter_alarm else []))
        else:
            level, text = OK, "no alarm"
        self.diagnostics.update(level, text, {
            **self.health(), **{f"{name}_theta": " ".join(f"{v:.4g}" for v in theta)
                              for name, theta in sample.theta.items()}})


    def health(self) -> dict[str, int]:
        return {**self.counts, "skipped_samples": self.detector.skipped_samples,
                "implausible_values": self.streams.implausible_values,
                "stamp_resets": self.streams.restarts, "stray_stamps": self.streams.stray_messages,
                "dropped_incomplete_samples": self.streams.dropped_sets,
                "late_optional_messages": self.streams.late_optional}


def main(args: list[str] | None = None) -> int:
    return run_node("detector_node", DetectorNode, args=args)


if __name__ == "__main__":
    sys.exit(main())
